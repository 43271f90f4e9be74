"""The parameter list of a camera definition file: what the emulator serves and what the client reads.

Only the facts the PARAM_EXT exchange needs: name, type, default, options (value and label), range. The
XML is parsed with cdf.xmlsafe (no DTD, no entities, no network, bounded depth); a file that a definition
validator would reject in other ways is still read as far as it can be, so the client can show what it has.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cdf.errors import CdfError
from cdf.xmlsafe import MAX_BYTES, inflate, parse_xml


@dataclass(frozen=True)
class DefOption:
    value: float | int
    label: str


@dataclass(frozen=True)
class DefParam:
    name: str
    type: str
    default: float | int | None
    description: str = ""
    options: tuple[DefOption, ...] = ()
    min: float | None = None
    max: float | None = None
    step: float | None = None
    control: bool = True        # control="0": the GCS shows no control (a read-only or mode parameter)

    @property
    def integer(self) -> bool:
        return self.type.lower() not in ("float", "double")

    def label_of(self, value: float | int | None) -> str | None:
        if value is None:
            return None
        return next((o.label for o in self.options if o.value == value), None)

    def check(self, value: float | int) -> str | None:
        """Why `value` is not allowed by the definition, or None when it is."""
        if isinstance(value, float) and not math.isfinite(value):
            return "not a finite number"
        if self.integer and value != int(value):
            return "not a whole number"
        if self.options:
            if not any(o.value == value for o in self.options):
                return "not one of the options " + ", ".join(f"{o.label} ({_num(o.value)})" for o in self.options)
            return None
        if self.min is not None and value < self.min:
            return f"below the minimum {_num(self.min)}"
        if self.max is not None and value > self.max:
            return f"above the maximum {_num(self.max)}"
        return None


@dataclass(frozen=True)
class Definition:
    vendor: str
    model: str
    version: int | None
    params: tuple[DefParam, ...]

    def param(self, name: str) -> DefParam | None:
        return next((p for p in self.params if p.name == name), None)


def _num(v: float | int) -> str:
    return str(int(v)) if float(v).is_integer() else f"{v:g}"


def _number(text: str | None, integer: bool) -> float | int | None:
    if text is None or not text.strip():
        return None
    try:
        v = float(text.strip())
    except ValueError:
        return None
    if integer and v.is_integer():
        return int(v)
    return v


def parse_definition(data: bytes, name: str = "definition") -> Definition:
    """Read a camera definition (plain or .xml.xz bytes); CdfError when it is not a readable definition."""
    loaded = inflate(data, name)
    if loaded.data is None:
        raise CdfError(loaded.problems[0].message if loaded.problems else "unreadable", where=name,
                       hint=f"a definition is plain XML or one whole .xml.xz stream of at most "
                            f"{MAX_BYTES // 2**20} MiB: check it with `wiris cdf validate`")
    root, problems = parse_xml(loaded.data, name)
    if root is None:
        p = problems[0] if problems else None
        raise CdfError(p.message if p else "not XML", where=f"{name}:{p.line}" if p and p.line else name,
                       hint="the camera serves a broken definition; report it to the camera's vendor")
    if root.tag != "mavlinkcamera":
        raise CdfError(f"root element is <{root.tag}>, not <mavlinkcamera>", where=name,
                       hint="this XML is not a camera definition: check which file the URI or path names")
    d = root.find("definition")
    version = None
    if d is not None:
        try:
            version = int(d.get("version", ""))
        except ValueError:
            version = None
    vendor = (d.findtext("vendor") or "").strip() if d is not None else ""
    model = (d.findtext("model") or "").strip() if d is not None else ""
    params = []
    seen = set()
    for p in root.iterfind("parameters/parameter"):
        pname = (p.get("name") or "").strip()
        ptype = (p.get("type") or "").strip().lower()
        if not pname or pname in seen:
            continue
        seen.add(pname)
        integer = ptype not in ("float", "double")
        options = []
        for o in p.iterfind("options/option"):
            v = _number(o.get("value"), integer)
            if v is not None:
                options.append(DefOption(v, (o.get("name") or "").strip() or str(v)))
        params.append(DefParam(
            name=pname, type=ptype, default=_number(p.get("default"), integer),
            description=(p.findtext("description") or "").strip(), options=tuple(options),
            min=_number(p.get("min"), False), max=_number(p.get("max"), False), step=_number(p.get("step"), False),
            control=p.get("control", "1").strip() != "0"))
    return Definition(vendor=vendor, model=model, version=version, params=tuple(params))
