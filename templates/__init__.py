"""The one loader for the jinja2 templates in this directory (camera definition XML, ArduPilot Lua bridge,
HTML preview).

    from templates import render
    text = render("camera_definition.xml.j2", camera=view)

Rules every template here gets, so nobody has to remember them:
- StrictUndefined: a misspelt or missing variable is an error, never an empty string in a file that
  flies (an empty <description> crashes MAVSDK, reference §D).
- Autoescape by the name under the `.j2` suffix: `.xml`, `.html`, `.htm`, `.svg`, `.kml` are escaped; Lua and
  other text templates are not. Autoescape is a safety net: generators should hand in strings that need no
  escaping, because QGroundControl's localisation compares raw bytes and never matches `&amp;` (reference §3.4).
- Deterministic output: no auto-reload, no caching by mtime, a trailing newline kept, block whitespace trimmed;
  a template renders the same bytes for the same values (published definitions are compared by sha256).
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

TEMPLATES_DIR = Path(__file__).resolve().parent

ESCAPED_SUFFIXES = (".xml", ".html", ".htm", ".svg", ".kml")


def _autoescape(name: str | None) -> bool:
    if name is None:
        return False
    return name.lower().removesuffix(".j2").endswith(ESCAPED_SUFFIXES)


def xml_comment(text: Any) -> Any:
    """Text made safe for inside an XML comment: `--` may not occur there (XML 1.0 §2.5) and a comment may
    not end in `-`. Returned as markup so autoescape leaves it alone (an `&#39;` in a comment stays literal)."""
    from markupsafe import Markup

    s = str(text)
    while "--" in s:
        s = s.replace("--", "- -")
    if s.endswith("-"):
        s += " "
    return Markup(s)


@functools.lru_cache(maxsize=1)
def environment():
    """The shared jinja2 Environment over this directory (built once per process; templates are data)."""
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES_DIR), encoding="utf-8"),
        undefined=jinja2.StrictUndefined,
        autoescape=_autoescape,
        auto_reload=False,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        newline_sequence="\n",
    )
    env.filters["xml_comment"] = xml_comment
    return env


def get_template(name: str):
    """A template of this directory by file name (jinja2.TemplateNotFound if there is none)."""
    return environment().get_template(name)


def render(name: str, **context: Any) -> str:
    """Render one template of this directory with `context`."""
    return get_template(name).render(**context)


__all__ = ["TEMPLATES_DIR", "environment", "get_template", "render", "xml_comment"]
