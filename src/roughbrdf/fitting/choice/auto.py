"""``--model auto``: the candidates of :func:`~roughbrdf.fitting.choice.compare.compare`, the best
kept, with a candidate far behind skipped after the first channel.

:func:`fit_auto` (``rb.fit("auto", ...)``) ranks the candidates as
:func:`~roughbrdf.fitting.choice.compare.compare` does (by the leave-one-incidence-out score; BIC
without one) and returns the best fit with the comparison attached. With the score, several
channels and at least two candidates, it works in two stages (``docs/fitting.md``, "Model
choice"):

1. every candidate is fitted to the first channel, with that channel's held-out residuals;
2. a candidate whose first-channel score is more than :data:`SKIP_MARGIN` above the best
   first-channel score (of the candidates whose fit neither gains energy nor has a parameter
   on a search limit) is not fitted further: its row keeps the first channel's figures and
   says so (:attr:`~roughbrdf.fitting.choice.compare.Candidate.partial`), and it ranks after
   every whole candidate. So is a candidate with a parameter on a search limit on the first
   channel (while another has none): the whole fit would have it too and rank after every
   candidate without one, whatever its score; its first-channel folds are not computed
   either (the row has no CV score and ranks after the scored ones). The others are fitted
   to the remaining channels, the search going on from the first channel as in one whole
   fit (the same subsample draws, the first channel's optimum as the warm start: the fit is
   the one ``compare`` makes), and scored over all channels as ``compare`` scores them, the
   first channel's folds not refitted.
3. parsimony: a candidate that goes on is still not fitted further when another that goes on
   has fewer free parameters (on the first channel) and the candidate does not predict the
   first channel at least :data:`PARSIMONY_MARGIN` better: its extra parameters would have to
   buy a clearly better prediction on the whole file to win there, and on the first channel
   they did not (its row says so and ranks after every whole candidate).

Why: model choice cost 12x one ``coated`` fit, and a candidate that predicts the first channel
3x worse than the best (TR75 on the shared paints) never won on the whole file. The margin is
measured (``scripts/auto_margin.py``): on the three shared paints the skipped candidates'
first-channel scores are 1.5x to 3.3x the best's, the kept ones' within 1.13x, and the choice
is the one of the whole comparison. The parsimony margin likewise: the two-lobe candidates
predicted the first channel 0-3 % better than ``coated`` on the shared paints, and none of them
won on the whole file (their whole-file scores within 1-2 % of it, or with a parameter on a
search limit); their whole fits were half of ``--model auto``'s time.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError
from ...models import Model, spec_text
from ..kinds.channels import fit_model, is_mueller
from ..problem.options import FitOptions
from ..problem.plan import channel_indices
from ..results.intervals import add_profiles
from ..results.plausibility import EnergyWarning, warn_energy
from .compare import (
    Candidate,
    as_candidates,
    candidate,
    compare,
    comparison,
    held_out_residuals,
    rms,
    score_metric,
)

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ..results.result import FitResult

__all__ = ["fit_auto", "SKIP_MARGIN", "PARSIMONY_MARGIN"]

#: a candidate whose first-channel score exceeds the best first-channel score by more than this
#: fraction is not fitted to the other channels (module notes; measured on the shared paints:
#: the candidates that lost were 1.5x and more above the best, the closest that won 0.13 above)
SKIP_MARGIN = 0.5

#: a candidate with more free parameters than another that goes on must predict the first
#: channel at least this fraction better than it to be fitted to the other channels (module
#: notes; measured on the shared paints: the two-lobe candidates' gains over ``coated`` there
#: were 0-3 %, and neither won on the whole file)
PARSIMONY_MARGIN = 0.05


def fit_auto(measurement: Measurement, candidates: Sequence[Model | str] | str | None = None,
             *, cv: bool = True, options: FitOptions | None = None,
             **keywords: Any) -> FitResult:
    """``rb.fit("auto", ...)``: the candidates compared (module notes), the best returned
    (by the cross-validation score, BIC without one;
    :func:`~roughbrdf.fitting.choice.compare.rank`), with the comparison attached
    (``FitResult.model_choice``: in ``fit.json``, the report and ``compare.png``).
    ``options`` and ``keywords`` as for :func:`~roughbrdf.fitting.choice.compare.compare`; ``fix``
    and ``bounds`` are refused (ArgumentError)."""
    if options is None:  # a progress bar per candidate only when asked for
        keywords = {"progress": False, **keywords}
    given = FitOptions.of(options, keywords, caller="fit_auto")
    for name in ("fix", "bounds"):
        value = getattr(given, name)
        if value:
            raise ArgumentError(name, "names parameters of one model; with model 'auto' the "
                                "candidates have different parameters: choose the model, or "
                                "compare candidates (rb.compare)", value=value)
    with warnings.catch_warnings():  # the candidates not chosen do not matter: the best's below
        warnings.simplefilter("ignore", EnergyWarning)
        models = as_candidates(candidates)
        if _staged(measurement, given, cv, len(models)):
            choice = _in_two_stages(measurement, models, given)
        else:
            choice = compare(measurement, models, cv=cv, options=given)
    best = choice.best.result
    if not given.joint and not is_mueller(measurement):  # the kept fit's alone, if asked
        add_profiles(best, measurement, given)
    warn_energy(best, stacklevel=3)
    best.model_choice = choice
    best.model_name = choice.best.label
    best.elapsed = sum(c.result.elapsed for c in choice.candidates)
    return best


def _staged(measurement: Measurement, options: FitOptions, cv: bool, n_models: int) -> bool:
    """Whether the two stages apply: a score, channels fitted one by one, several of them,
    several incidences and candidates."""
    if not cv or options.joint or is_mueller(measurement):
        return False
    if measurement.incidences().size < 2:
        return False
    return n_models >= 2 and len(channel_indices(measurement, options.channel)) >= 2


def _in_two_stages(measurement: Measurement, models: list[Model], options: FitOptions) -> Any:
    """The :class:`~roughbrdf.fitting.choice.compare.ModelComparison` of the two stages (module
    notes)."""
    metric, losses = score_metric(models, options)
    first = channel_indices(measurement, options.channel)[0]
    opt1 = options.replace(channel=[first])
    fits = [fit_model(m, measurement, opt1, check_energy=False) for m in models]
    # a search limit on the first channel stays one of the whole fit: it would rank after
    # every candidate without one (compare.rank), whatever its score; so it is not scored
    # (its folds would be spent on a row that cannot win) while another candidate has none
    limited = [r.at_search_limit for r in fits]
    stop_limited = not all(limited)
    rows: list[Candidate] = []
    helds: list[np.ndarray | None] = []
    for m, res, lim in zip(models, fits, limited, strict=True):
        label = spec_text(m)
        if stop_limited and lim:
            rows.append(candidate(label, res, None, partial=(
                f"fitted to channel {res.channels[0].channel} only, not scored: "
                f"{', '.join(res.search_limits)} on a search limit there; it would rank after "
                f"the candidates without one")))
            helds.append(None)
            continue
        held = held_out_residuals(res, opt1, label=label, metric=metric)
        helds.append(held)
        rows.append(candidate(label, res, rms(held)))
    scores = [math.nan if h is None else rms(h) for h in helds]
    skips = _skipped(rows, scores, limited)
    out: list[Candidate] = []
    for m, first_row, first_held, why in zip(models, rows, helds, skips, strict=True):
        label, res = first_row.label, first_row.result
        if first_held is None:  # stopped on a search limit (above)
            out.append(first_row)
            continue
        if why is not None:
            out.append(dataclasses.replace(first_row, partial=(
                f"fitted to channel {res.channels[0].channel} only: {why}")))
            continue
        # the other channels, the search going on from the first as in one whole fit: the
        # same fit as compare's, and the first channel's folds are not refitted
        whole = fit_model(m, measurement, options, check_energy=False, done=res.channels)
        whole.elapsed += res.elapsed
        more = dataclasses.replace(whole, channels=whole.channels[1:])
        held_all = np.concatenate([first_held, held_out_residuals(more, options, label=label,
                                                            metric=metric)])
        out.append(candidate(label, whole, rms(held_all)))
    return comparison(out, measurement, losses)


def _skipped(rows: list[Candidate], scores: list[float], limited: list[bool]
             ) -> list[str | None]:
    """Why each first-channel candidate is not fitted further (None: it is): its score more
    than :data:`SKIP_MARGIN` above the best, or not :data:`PARSIMONY_MARGIN` below that of a
    candidate with fewer free parameters that goes on (module notes). NaN scores are skipped."""
    # the margin is counted from the best candidate that can be kept: not one that gains
    # energy or stopped on a search limit (both rank after the others, compare.rank)
    sound = [not r.gains_energy and not lim for r, lim in zip(rows, limited, strict=True)]
    pool = [s for s, ok in zip(scores, sound, strict=True) if ok]
    pool = pool or [s for s in scores if not math.isnan(s)]
    best = min(pool) if pool else math.nan  # NaN: no score, every candidate skipped below
    why: list[str | None] = []
    for score in scores:
        within = score <= best * (1 + SKIP_MARGIN)  # NaN: False, skipped
        why.append(None if within else (f"its score there ({score:.4g}) is more than "
                                        f"{SKIP_MARGIN:.0%} above the best's ({best:.4g})"))
    free = [len(r.result.channels[0].free) for r in rows]
    for i, score in enumerate(scores):
        if why[i] is not None:
            continue
        simpler = [j for j in range(len(rows)) if why[j] is None and sound[j]
                   and free[j] < free[i] and not score < scores[j] * (1 - PARSIMONY_MARGIN)]
        if simpler:
            j = min(simpler, key=lambda j: scores[j])
            why[i] = (f"with {free[i]} free parameters it predicts there no more than "
                      f"{PARSIMONY_MARGIN:.0%} better ({score:.4g}) than {rows[j].label} "
                      f"with {free[j]} ({scores[j]:.4g})")
    return why
