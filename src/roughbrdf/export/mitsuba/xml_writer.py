"""The XML ``<bsdf>`` element of a Mitsuba 3 scene file, from a scene-description dict."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

__all__ = ["xml_text"]


def _xml_property(parent: ET.Element, name: str, value: Any) -> None:
    if isinstance(value, dict) and value.get("type") in ("rgb", "srgb"):
        rgb = ", ".join(repr(float(x)) for x in (value["color"] if "color" in value
                                                 else value["value"]))
        if not value.get("unbounded"):
            ET.SubElement(parent, "rgb", name=name, value=rgb)
            return
        tex = ET.SubElement(parent, "texture", type="srgb", name=name)
        ET.SubElement(tex, "rgb", name="color", value=rgb)
        ET.SubElement(tex, "boolean", name="unbounded", value="true")
    elif isinstance(value, dict):
        parent.append(_xml_element(value, name))
    elif isinstance(value, bool):
        ET.SubElement(parent, "boolean", name=name, value="true" if value else "false")
    elif isinstance(value, int | float):
        ET.SubElement(parent, "float", name=name, value=repr(float(value)))
    else:
        ET.SubElement(parent, "string", name=name, value=str(value))


def _xml_element(bsdf: dict[str, Any], name: str | None = None) -> ET.Element:
    el = ET.Element("bsdf", type=str(bsdf["type"]))
    if name is not None:
        el.set("name", name)
    for key, value in bsdf.items():
        if key != "type":
            _xml_property(el, key, value)
    return el


def xml_text(bsdf: dict[str, Any], id: str | None = None,  # noqa: A002
             version: str | None = None) -> str:
    """One BSDF dict as an XML ``<bsdf>`` element; ``version="3.0.0"`` makes it a document
    Mitsuba loads on its own (``mitsuba.load_string``)."""
    el = _xml_element(bsdf)
    if version is not None:
        el.set("version", str(version))
    if id:
        el.set("id", str(id))
    ET.indent(el)
    return ET.tostring(el, encoding="unicode")
