"""Render a fitted paint from its RGL file and from the model itself, and compare the images.

The second "Must show" of issue 29 (``docs/export.md``, "Rendered: the RGL file against the
model"): a coated fit of one shared Mini-Diff paint (one channel, 525 nm: a grey material) is
exported with ``to="rgl"`` (default resolution) and a sphere is rendered with Mitsuba 3
(``scalar_rgb``, ``direct`` integrator: one emitter sample and one BSDF sample per pass, MIS)
under a constant environment (radiance 1) and a point light, seen by an orthographic camera:

* **rgl**: Mitsuba's own ``measured`` plugin reading the file (it importance-samples the file's
  luminance warp);
* **direct**: :class:`ModelBSDF`, a Mitsuba BSDF written in Python (``mi.BSDF``, registered
  as ``"roughbrdf_model"``) whose ``eval`` is the model's ``brdf(theta_i, theta_o, phi) *
  cos(theta_o)`` and whose ``sample`` draws half of its directions from GGX visible normals
  with the model's own ``alpha`` and half cosine-weighted (``pdf`` the mixture's density,
  the weight ``eval / pdf``): sampling only, which sets the noise, not the mean.

In a scalar variant Mitsuba calls a Python BSDF once per direction, and one model evaluation
costs about 0.2 ms against 0.2 us per direction in a NumPy batch (the LLVM variants, which
would batch, do not run on this machine). So the direct render is done twice with the same
seed: a *record* pass whose ``eval``/``sample`` return placeholders and note every direction
pair asked for, one vectorized ``model.brdf`` over all of them, and a *replay* pass that returns
those values (keyed by the exact float32 directions; a pair not found is evaluated on the
spot and counted). The ``direct`` integrator's random numbers and rays do not depend on the
BSDF's values, so the replay asks for the same pairs (the script prints the misses: 0).

Each plugin is rendered with seeds 1 and 2; the **relative RMSE** of image ``a`` against
image ``b`` is ``sqrt(mean((a - b)**2)) / mean(b)`` over the pixels that lie wholly inside
the sphere's outline (one channel: the material is grey), and the table gives it for every
pair. The issue's bound: rgl-vs-direct (same seed, and different seeds) at most twice
direct-vs-direct (the seed noise). Each render's own noise is its two seeds' relative RMSE
over sqrt(2). The side-by-side image (rgl | direct | 8 x |difference|) goes to
``docs/img/rgl_render.png``.

Run (the defaults made the figure of ``docs/export.md``: about 22 minutes on a loaded 2-core
machine, of which 8-14 minutes each direct render and its record pass, 10 s each rgl render,
a few seconds the fit; the time grows with ``size**2 * spp``, ``--spp 64`` takes about 3
minutes; memory: about 0.5 kB per recorded pair, 4.9 million pairs, some 2.5 GB, at the
defaults)::

    ROUGHBRDF_SHARED_DATA=../shared/data .venv/bin/python scripts/render_rgl.py \\
        [--paint C8_Silver] [--channel 525nm] [--size 96] [--spp 512] \\
        [--out docs/img/rgl_render.png]

``tests/export/test_export_rgl_render.py`` runs :func:`compare` small (32 x 32, 16 spp) in
CI, on a synthetic coated model and on this fit of C8_Silver.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import struct
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import roughbrdf as rb
from roughbrdf.export.rgl import to_rgl

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", HERE.parent.parent / "shared" / "data"))
#: the half-width of the orthographic view (the sphere's radius is 1)
VIEW = 1.1
#: the point light: position and intensity (W/sr); the environment's radiance is 1
LIGHT = ((-2.0, 2.5, 3.0), 15.0)

_MODELS: dict[str, Any] = {}  # the models the "roughbrdf_model" plugins evaluate, by key
#: the share of the Python plugin's samples drawn from GGX visible normals (the rest: cosine)
GLOSSY_SHARE = 0.5


def sampling_alpha(model: Any) -> float | None:
    """The GGX ``alpha`` the Python plugin samples with: the model's own ``alpha`` (the
    coated models' Trowbridge-Reitz coat is GGX) when it has one, else ``None`` (cosine-weighted
    sampling alone). Sampling only: the values are the model's whichever it is."""
    alpha = getattr(model, "params", {}).get("alpha")
    return float(np.clip(alpha, 0.02, 1.0)) if isinstance(alpha, int | float) else None


def _mitsuba():
    import mitsuba as mi

    if mi.variant() != "scalar_rgb":
        mi.set_variant("scalar_rgb")
    return mi


def angles(wi: np.ndarray, wo: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The library's ``(theta_i, theta_o, phi)`` of Mitsuba local directions ``(N, 3)``
    (``phi = 0`` forward: ``wo`` opposite ``wi`` in azimuth), as ``tests/export/
    test_export_rgl.py`` maps them."""
    ti = np.arccos(np.clip(wi[:, 2], 0.0, 1.0))
    to = np.arccos(np.clip(wo[:, 2], 0.0, 1.0))
    phi = np.arctan2(wo[:, 1], wo[:, 0]) - np.arctan2(wi[:, 1], wi[:, 0]) - math.pi
    return ti, to, (phi + math.pi) % (2 * math.pi) - math.pi


def model_eval(model: Any, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """``f_r cos(theta_o)`` of ``model`` at Mitsuba local directions (0 below the horizon)."""
    out = np.zeros(len(wi))
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    if up.any():
        ti, to, phi = angles(wi[up], wo[up])
        out[up] = np.asarray(model.brdf(ti, to, phi), float) * wo[up, 2]
    return out


@dataclass
class Cache:
    """The record / replay store of :class:`ModelBSDF`: ``mode`` is "record" or "replay"."""

    model: Any
    mode: str = "record"
    asked: dict[bytes, float] = field(default_factory=dict)
    misses: int = 0

    def fill(self) -> None:
        """Evaluate the model once, vectorized, at every recorded pair; then replay."""
        keys = list(self.asked)
        pairs = np.frombuffer(b"".join(keys), "<f4").astype(float).reshape(-1, 6)
        values = model_eval(self.model, pairs[:, :3], pairs[:, 3:])
        self.asked = dict(zip(keys, values.tolist(), strict=True))
        self.mode = "replay"

    def value(self, wi: Any, wo: Any) -> float:
        key = struct.pack("<6f", wi[0], wi[1], wi[2], wo[0], wo[1], wo[2])
        if self.mode == "record":
            self.asked[key] = 0.0
            return 1.0  # a placeholder: the direct integrator does not branch on it
        found = self.asked.get(key)
        if found is None:  # not asked for in the record pass: evaluate it here
            self.misses += 1
            found = float(model_eval(self.model, np.array([list(wi)], float),
                                     np.array([list(wo)], float))[0])
        return found


def register() -> None:
    """Register the ``"roughbrdf_model"`` Mitsuba BSDF (property ``key``: a model or
    :class:`Cache` in :data:`_MODELS`)."""
    import drjit as dr

    mi = _mitsuba()

    class ModelBSDF(mi.BSDF):
        """A roughbrdf model as a Mitsuba BSDF: ``eval = f_r cos(theta_o)``; ``sample`` and
        ``pdf``: :data:`GLOSSY_SHARE` GGX visible normals (:func:`sampling_alpha`), the rest
        cosine-weighted; one-sided, like the ``measured`` plugin."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            held = _MODELS[props["key"]]
            self.cache = held if isinstance(held, Cache) else None
            self.model = held.model if isinstance(held, Cache) else held
            alpha = sampling_alpha(self.model)
            self.ggx = (None if alpha is None
                        else mi.MicrofacetDistribution(mi.MicrofacetType.GGX, alpha))
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _f(self, wi, wo) -> float:
            if wi[2] <= 0 or wo[2] <= 0:
                return 0.0
            if self.cache is not None:
                return self.cache.value(wi, wo)
            return float(model_eval(self.model, np.array([list(wi)], float),
                                    np.array([list(wo)], float))[0])

        def eval(self, ctx, si, wo, active=True):
            v = self._f(si.wi, wo)
            return mi.Color3f(v, v, v)

        def pdf(self, ctx, si, wo, active=True):
            wi = si.wi
            if wi[2] <= 0 or wo[2] <= 0:
                return 0.0
            cosine = float(wo[2]) / math.pi
            if self.ggx is None:
                return cosine
            m = dr.normalize(wi + wo)
            glossy = float(self.ggx.pdf(wi, m)) / (4 * float(dr.dot(wo, m)))
            return GLOSSY_SHARE * glossy + (1 - GLOSSY_SHARE) * cosine

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = mi.BSDFSample3f()
            if self.ggx is not None and sample1 < GLOSSY_SHARE:
                m, _ = self.ggx.sample(si.wi, sample2)
                wo = mi.reflect(si.wi, m)
            else:
                wo = mi.warp.square_to_cosine_hemisphere(sample2)
            if si.wi[2] <= 0 or wo[2] <= 0:
                return bs, mi.Color3f(0.0)
            bs.wo, bs.pdf, bs.eta = wo, self.pdf(ctx, si, wo), 1.0
            bs.sampled_type = int(mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = 0
            f = self._f(si.wi, wo)  # f_r cos(theta_o)
            w = f / bs.pdf if self.cache is None or self.cache.mode == "replay" else 1.0
            return bs, mi.Color3f(w, w, w)

        def traverse(self, callback):
            pass

        def to_string(self):
            return f"ModelBSDF[{self.model!r}]"

    mi.register_bsdf("roughbrdf_model", lambda props: ModelBSDF(props))


def model_bsdf(model: Any) -> Any:
    """The ``"roughbrdf_model"`` Mitsuba BSDF of ``model`` (evaluated at every call)."""
    mi = _mitsuba()
    register()
    key = f"model-{id(model)}"
    _MODELS[key] = model
    try:
        return mi.load_dict({"type": "roughbrdf_model", "key": key})
    finally:
        del _MODELS[key]


def scene(bsdf: dict, size: int, spp: int) -> Any:
    """The sphere under the constant environment and the point light."""
    mi = _mitsuba()
    T = mi.ScalarTransform4f
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 1},
        "sphere": {"type": "sphere", "radius": 1.0, "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        "light": {"type": "point", "position": list(LIGHT[0]),
                  "intensity": {"type": "rgb", "value": LIGHT[1]}},
        "sensor": {"type": "orthographic",
                   "to_world": T().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0])
                   @ T().scale([VIEW, VIEW, 1.0]),
                   "film": {"type": "hdrfilm", "width": size, "height": size,
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
    })


def mask(size: int) -> np.ndarray:
    """Pixels wholly inside the sphere's outline (all four corners within radius 1)."""
    edges = np.linspace(-VIEW, VIEW, size + 1)
    far = np.maximum(np.abs(edges[:-1]), np.abs(edges[1:]))  # each pixel's farthest corner
    return far[:, None] ** 2 + far[None, :] ** 2 < 1.0


def render(bsdf: dict, size: int, spp: int, seed: int) -> np.ndarray:
    """One channel of one render (the material is grey), ``(size, size)``."""
    mi = _mitsuba()
    image = np.array(mi.render(scene(bsdf, size, spp), seed=seed))
    return image[..., 1].astype(float)


def render_direct(model: Any, size: int, spp: int, seed: int) -> tuple[np.ndarray, dict]:
    """The direct render by record and replay (:class:`Cache`), and its counts."""
    register()
    key = f"model-{id(model)}-{seed}"
    cache = _MODELS[key] = Cache(model)
    try:
        render({"type": "roughbrdf_model", "key": key}, size, spp, seed)  # record
        t = time.perf_counter()
        cache.fill()
        fill = time.perf_counter() - t
        image = render({"type": "roughbrdf_model", "key": key}, size, spp, seed)  # replay
    finally:
        del _MODELS[key]
    return image, {"pairs": len(cache.asked), "misses": cache.misses, "fill_s": fill}


def relative_rmse(a: np.ndarray, b: np.ndarray, inside: np.ndarray) -> float:
    """``sqrt(mean((a - b)**2)) / mean(b)`` over the pixels ``inside``."""
    return float(np.sqrt(np.mean((a[inside] - b[inside]) ** 2)) / np.mean(b[inside]))


@dataclass
class Comparison:
    images: dict[str, np.ndarray]
    table: dict[str, float]
    notes: dict[str, Any]

    def text(self) -> str:
        rows = ["| images | relative RMSE |", "|---|---|"]
        rows += [f"| {k} | {v:.4f} |" for k, v in self.table.items()]
        return "\n".join(rows)


def compare(model: Any, source: Any = None, *, size: int = 96, spp: int = 512,
            resolution: dict | None = None, folder: str | os.PathLike | None = None,
            log: Callable[[str], None] = lambda s: None) -> Comparison:
    """Export ``source`` (default ``model``) to RGL, render rgl and direct with seeds 1 and 2,
    and compute the relative RMSE of every pair that the bound uses."""
    folder = Path(folder or tempfile.mkdtemp())
    done = to_rgl(model if source is None else source, folder / "paint.bsdf",
                  resolution=resolution, overwrite=True)
    log(done.text())
    images, notes = {}, {"rgl_file": done.text()}
    for seed in (1, 2):
        t = time.perf_counter()
        images[f"rgl{seed}"] = render({"type": "measured", "filename": str(done.path)},
                                      size, spp, seed)
        notes[f"rgl{seed}_s"] = time.perf_counter() - t
        log(f"rgl, seed {seed}: {notes[f'rgl{seed}_s']:.1f} s")
        t = time.perf_counter()
        images[f"direct{seed}"], counts = render_direct(model, size, spp, seed)
        notes[f"direct{seed}_s"] = time.perf_counter() - t
        notes[f"direct{seed}_counts"] = counts
        log(f"direct, seed {seed}: {notes[f'direct{seed}_s']:.1f} s ({counts})")
    inside = mask(size)
    notes["pixels"] = int(inside.sum())
    r = {
        "rgl seed 1 vs direct seed 1": relative_rmse(images["rgl1"], images["direct1"], inside),
        "rgl seed 2 vs direct seed 2": relative_rmse(images["rgl2"], images["direct2"], inside),
        "rgl seed 1 vs direct seed 2": relative_rmse(images["rgl1"], images["direct2"], inside),
        "direct seed 1 vs direct seed 2 (noise)": relative_rmse(images["direct1"],
                                                                images["direct2"], inside),
        "rgl seed 1 vs rgl seed 2 (noise)": relative_rmse(images["rgl1"], images["rgl2"],
                                                          inside),
    }
    mean_direct = 0.5 * (images["direct1"] + images["direct2"])
    mean_rgl = 0.5 * (images["rgl1"] + images["rgl2"])
    r["rgl mean vs direct mean (2 seeds each)"] = relative_rmse(mean_rgl, mean_direct, inside)
    notes["noise_direct"] = r["direct seed 1 vs direct seed 2 (noise)"] / math.sqrt(2)
    notes["noise_rgl"] = r["rgl seed 1 vs rgl seed 2 (noise)"] / math.sqrt(2)
    # what is left of the rgl-direct difference once both noises are taken out
    bias2 = (r["rgl seed 1 vs direct seed 2"] ** 2 - notes["noise_direct"] ** 2
             - notes["noise_rgl"] ** 2)
    notes["bias_estimate"] = math.sqrt(max(bias2, 0.0))
    notes["mean_direct"] = float(np.mean(mean_direct[inside]))
    notes["mean_rgl"] = float(np.mean(mean_rgl[inside]))
    return Comparison(images, r, notes)


def figure(c: Comparison, out: Path, title: str) -> None:
    """rgl | direct | 8 x |rgl - direct| (seed 1), tone-mapped alike, to ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a, b = c.images["rgl1"], c.images["direct1"]
    top = float(np.percentile(np.concatenate([a.ravel(), b.ravel()]), 99.5))

    def tone(x):
        return np.clip(x / top, 0, 1) ** (1 / 2.2)

    fig, axes = plt.subplots(1, 3, figsize=(7.5, 2.8), dpi=100)
    for ax, img, name in zip(axes, (tone(a), tone(b), tone(8 * np.abs(a - b))),
                             ("RGL file (Mitsuba 'measured')", "model (Python plugin)",
                              "8 x |difference|"), strict=True):
        ax.imshow(img, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        ax.set_title(name, fontsize=9)
        ax.axis("off")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--paint", default="C8_Silver")
    p.add_argument("--channel", default="525nm")
    p.add_argument("--size", type=int, default=96)
    p.add_argument("--spp", type=int, default=512)
    p.add_argument("--out", type=Path, default=HERE.parent / "docs" / "img" / "rgl_render.png")
    args = p.parse_args(argv)
    path = SHARED / "minidiff" / f"{args.paint}.astm"
    if not path.is_file():
        print(f"no {path}: set ROUGHBRDF_SHARED_DATA", file=sys.stderr)
        return 2
    mi = _mitsuba()
    t = time.perf_counter()
    fit = rb.fit("coated", rb.read(path), channel=args.channel, starts=1, progress=False)
    model = fit.channels[0].model
    print(f"fit of {args.paint} {args.channel} in {time.perf_counter() - t:.0f} s: {model!r}")
    c = compare(model, fit, size=args.size, spp=args.spp, log=print)
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    print(f"Mitsuba {mi.__version__} scalar_rgb, {args.size}x{args.size}, {args.spp} spp, "
          f"{c.notes['pixels']} pixels inside the sphere; {when}, "
          f"{platform.machine()} {os.cpu_count()} cores")
    print(c.text())
    n = c.notes
    print(f"noise per render (two seeds' relative RMSE / sqrt 2): "
          f"direct {n['noise_direct']:.4f}, "
          f"rgl {n['noise_rgl']:.4f}; rgl-direct difference beyond the noise: "
          f"{n['bias_estimate']:.4f}; mean radiance direct {n['mean_direct']:.4f}, "
          f"rgl {n['mean_rgl']:.4f}")
    noise = c.table["direct seed 1 vs direct seed 2 (noise)"]
    ratios = {pair: c.table[pair] / noise for pair in (
        "rgl seed 1 vs direct seed 1", "rgl seed 2 vs direct seed 2",
        "rgl seed 1 vs direct seed 2")}
    for pair, ratio in ratios.items():
        print(f"bound: {pair} / seed noise = {ratio:.2f} (must be <= 2)")
    t = c.table
    figure(c, args.out, f"{args.paint} {args.channel}, coated fit; {args.size}x{args.size}, "
           f"{args.spp} spp; relative RMSE rgl-direct {t['rgl seed 1 vs direct seed 1']:.3f}, "
           f"seeds {t['direct seed 1 vs direct seed 2 (noise)']:.3f}")
    print(f"wrote {args.out} ({args.out.stat().st_size / 1e3:.0f} kB)")
    return 0 if max(ratios.values()) <= 2 else 1


if __name__ == "__main__":
    sys.exit(main())
