"""Camera definition files (MAVLink CDF XML) generated from the camera catalogue.

    from cdf.catalogue import catalogue
    from cdf.generate import definition_xml, definition_file_name
    data = definition_xml(catalogue().get("wiris-pro"))        # bytes, UTF-8, byte-identical per rebuild

Every choice below is made so that both QGroundControl and MAVSDK accept every parameter
(shared/reference/camera-definition-files.md §C and §D):
- integer settings in canonical decimal (`-?[0-9]+`), floats in plain decimal notation (no exponent);
- no `bool` (QGC renders it "true"/"false", so exclusions keyed on it never fire) and no `uint16`
  (MAVSDK's camera plugin mishandles it); the catalogue's enumerations are uint32;
- a default that is exactly one of the options (MAVSDK rejects the whole file otherwise), min and max on
  every range parameter (MAVSDK drops it otherwise), `decimalPlaces` in camelCase (QGC ignores other
  spellings);
- exclusions from the catalogue's `hides`, re-requests from its `updates`, both only naming parameters
  that are in the definition;
- no XML entities: every text is checked to need no escaping, because QGC's localisation compares raw
  bytes and would never match `&amp;`;
- localisation (cdf/tables/locales/ll_CC.yaml, English label -> translation): QGC replaces every
  `"original"` and `>original<` in the whole file, so an original may only be a description or an option
  name and must not equal any other attribute value or element text (parameter names, values, types,
  units, model, vendor, exclude/update texts); a translation must not itself be another original (QGC
  applies the strings one after another).
- no CAM_MODE: the camera takes MAV_CMD_SET_CAMERA_MODE, which QGC sends when the definition has no
  CAM_MODE (rationale in the template header and docs/camera-definitions.md).
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path
from typing import Iterable, NamedTuple

from cdf.catalogue import CDF_TYPES, INTEGER_RANGES, PARAM_NAME_MAX, Camera, Catalogue, Setting, short_list
from cdf.errors import CdfError

TEMPLATE = "camera_definition.xml.j2"
LOCALES_DIR = Path(__file__).resolve().parent / "tables" / "locales"
# QGC matches locales as ll_CC (lower-cased, '-' -> '_'), falling back to the first three characters
# ("de_"): a bare "de" never matches (reference §3.4).
LOCALE_NAME = re.compile(r"^[a-z]{2}_[A-Z]{2}$")
# Types both parsers handle fully: the catalogue's (no bool: QGC exclusions; no string/custom: MAVSDK skips)
# but uint16, which MAVSDK's camera plugin mishandles.
GENERATED_TYPES = tuple(t for t in CDF_TYPES if t != "uint16")
# Characters that would need an XML entity in an attribute or text (QGC's byte-wise localisation and
# MAVSDK, which shows entities literally, both need the raw text).
XML_SPECIAL = frozenset('&<>"\'')
# CAMERA_INFORMATION.vendor_name / model_name are uint8_t[32]: 31 bytes and a NUL (common.xml).
IDENTITY_MAX_BYTES = 31
# CAMERA_INFORMATION.cam_definition_version is uint16_t (common.xml); 0 means "unknown" and is never cached right.
VERSION_RANGE = (1, 65535)


@dataclass(frozen=True)
class Locale:
    """One translation table: English label or option name -> translation."""

    name: str
    strings: tuple[tuple[str, str], ...]
    path: str = ""

    def translate(self, text: str) -> str | None:
        return dict(self.strings).get(text)


@dataclass(frozen=True)
class OptionView:
    name: str
    value: str
    excludes: tuple[str, ...] = ()


@dataclass(frozen=True)
class ParameterView:
    name: str
    type: str
    default: str
    attributes: tuple[tuple[str, str], ...]   # min, max, step, decimalPlaces, unit — in that order
    description: str
    comment: str
    updates: tuple[str, ...]
    options: tuple[OptionView, ...]


@dataclass(frozen=True)
class StringView:
    original: str
    translated: str


@dataclass(frozen=True)
class LocaleView:
    name: str
    strings: tuple[StringView, ...]


@dataclass(frozen=True)
class DefinitionView:
    """Everything the template needs, as ready-made strings (the template does no formatting)."""

    camera_id: str
    vendor: str
    model: str
    version: int
    table: str
    source: str
    parameters: tuple[ParameterView, ...]
    locales: tuple[LocaleView, ...]
    missing_translations: tuple[tuple[str, str], ...]   # (locale, English text) left in English


# ---------------------------------------------------------------------------------------------- locales

def load_locales(directory: Path | None = None) -> tuple[Locale, ...]:
    """Every cdf/tables/locales/ll_CC.yaml, sorted by locale name (the order QGC sees them in the file)."""
    return _load_locales(str(directory or LOCALES_DIR))


@functools.lru_cache(maxsize=4)
def _load_locales(directory: str) -> tuple[Locale, ...]:
    import yaml

    out = []
    for path in sorted(Path(directory).glob("*.yaml")):
        name = path.stem
        if not LOCALE_NAME.match(name):
            raise CdfError(f"locale file name {path.name!r} is not ll_CC.yaml", where=str(path),
                           hint="QGroundControl matches locales like de_DE or cs_CZ; rename the file")
        try:
            raw = yaml.safe_load(path.read_text(encoding="utf-8"))
        except yaml.YAMLError as err:
            raise CdfError(f"cannot parse locale table: {err}", where=str(path),
                           hint="fix the YAML at the line and column it names; quote texts with a colon") from None
        strings = (raw or {}).get("strings") if isinstance(raw, dict) else None
        if not isinstance(strings, dict):
            raise CdfError("a locale table needs a mapping `strings: {English: translation}`", where=str(path),
                           hint='start with `strings:`, then one indented `"English": "translation"` line per text')
        pairs = []
        for original, translated in strings.items():
            if not isinstance(original, str) or not isinstance(translated, str):
                raise CdfError(f"locale entry {original!r}: both sides must be text", where=str(path),
                               hint="quote values YAML would read as numbers or booleans (Off, On, Yes)")
            for text in (original, translated):
                _check_text(text, f"locale entry {original!r}", str(path))
            pairs.append((original, translated))
        out.append(Locale(name=name, strings=tuple(pairs), path=str(path)))
    return tuple(out)


# ------------------------------------------------------------------------------------------- formatting

def _check_text(text: str, what: str, where: str) -> None:
    if not text or text != text.strip():
        raise CdfError(f"{what}: empty or padded text {text!r}", where=where,
                       hint="MAVSDK crashes on empty descriptions; QGC matches strings byte for byte")
    bad = sorted(set(text) & XML_SPECIAL)
    if bad:
        raise CdfError(f"{what}: {text!r} contains {' '.join(bad)}, which XML would write as an entity",
                       where=where, hint="QGroundControl's localisation never matches entities; reword it")
    if any(ord(c) < 0x20 for c in text):
        raise CdfError(f"{what}: {text!r} contains a control character", where=where,
                       hint="write it on one line without tabs (a YAML `|` block keeps its line breaks)")


def _integer(s: Setting, value: float | int, where: str) -> str:
    if isinstance(value, bool) or int(value) != value:
        raise CdfError(f"setting {s.key}: {value!r} is not a whole number for {s.type}", where=where,
                       hint="write 1 or 0, not true or false" if isinstance(value, bool) else
                       "give `default:`, `min:`, `max:` and `step:` whole values, or make `type:` float")
    lo, hi = INTEGER_RANGES[s.type]
    if not lo <= int(value) <= hi:
        raise CdfError(f"setting {s.key}: {value} does not fit {s.type} ({lo}..{hi})", where=where,
                       hint="MAVSDK parses 32-bit values with std::stoi: keep them at most 2147483647")
    return str(int(value))


def _real(s: Setting, value: float | int, where: str) -> str:
    v = float(value)
    if not math.isfinite(v):
        raise CdfError(f"setting {s.key}: {value!r} is not a finite number", where=where,
                       hint="write finite numbers in `default:`, `min:`, `max:` and `step:` (no .inf or .nan)")
    if s.decimals is not None:
        text = f"{v:.{int(s.decimals)}f}"
        if float(text) == v:
            # what QGC shows with decimalPlaces, so a float written here equals QGC's rendering (rule 25)
            return text.lstrip("-") if float(text) == 0 else text
    return format(Decimal(repr(v)), "f")   # shortest round-trip form, never an exponent


def _number(s: Setting, value: float | int, where: str) -> str:
    return _integer(s, value, where) if s.is_integer else _real(s, value, where)


def _description(s: Setting) -> str:
    return f"{s.label} ({s.unit})" if s.unit else s.label


def _option_parts(s: Setting, option) -> tuple[str, ...]:
    """The flag names a combination option is joined from (its translation joins their translations)."""
    if s.flags and s.enum is not None:
        names = []
        for key in option.key.split("+"):
            flag = s.enum.by_key(key)
            if flag is None:
                return (option.name,)
            names.append(flag.name)
        if " + ".join(names) == option.name:
            return tuple(names)
    return (option.name,)


def _comment(s: Setting) -> str:
    parts = [f"{s.param}: plan setting {s.key}"]
    if s.source:
        parts.append(f"manual {s.source}")
    if s.command and s.command.cmd:
        slot = f"{s.command.cmd} param {s.command.param}"
        if s.command.offset:
            slot += f" (value {'+' if s.command.offset > 0 else '-'} {abs(s.command.offset)})"
        parts.append(f"sent as {slot}")
    return "; ".join(parts)


# ----------------------------------------------------------------------------------------------- views

class _Values(NamedTuple):
    """A parameter's formatted default, its attributes (unit, or min/max/step/decimalPlaces/unit) and options."""

    default: str
    attributes: tuple[tuple[str, str], ...]
    options: tuple[OptionView, ...]


def definition_view(camera: Camera, locales: Iterable[Locale] | None = None) -> DefinitionView:
    """The checked, formatted content of one camera's definition (CdfError on anything a parser would refuse)."""
    where = f"cdf/tables/{camera.table}" if camera.table else camera.id
    version = _checked_identity(camera, where)
    settings = camera.cdf_settings
    if not settings:
        raise CdfError(f"{camera.id}: no settings for the definition", where=where,
                       hint="QGroundControl rejects a definition without parameters")
    in_cdf = {s.param for s in settings}
    params = [_parameter_view(s, in_cdf, f"{where}: setting {s.key}") for s in settings]
    locale_views, missing = _localize(camera, settings, params, tuple(locales if locales is not None else load_locales()),
                                      where)
    return DefinitionView(camera_id=camera.id, vendor=camera.vendor, model=camera.model, version=version,
                          table=camera.table, source=camera.source, parameters=tuple(params),
                          locales=locale_views, missing_translations=missing)


def _checked_identity(camera: Camera, where: str) -> int:
    """The definition version, after checking the camera has a definition and fits CAMERA_INFORMATION."""
    if not camera.has_cdf:
        raise CdfError(f"{camera.id} ({camera.vendor} {camera.model}) has no camera definition", where=where,
                       hint="it does not speak the MAVLink camera protocol (RedEdge uses its serial API with "
                            "classic PARAM_*); build the Workswell models, or use --all to skip it")
    version = camera.definition_version
    if not isinstance(version, int) or isinstance(version, bool) or not VERSION_RANGE[0] <= version <= VERSION_RANGE[1]:
        raise CdfError(f"{camera.id}: definition_version {version!r} must be an integer 1..65535", where=where,
                       hint="CAMERA_INFORMATION.cam_definition_version is uint16; 0 would never refresh caches")
    for what, text in (("vendor", camera.vendor), ("model", camera.model)):
        _check_text(text, f"{camera.id} {what}", where)
        if len(text.encode("utf-8")) > IDENTITY_MAX_BYTES or any(c in text for c in "/\\:"):
            raise CdfError(f"{camera.id}: {what} {text!r} must be at most {IDENTITY_MAX_BYTES} bytes without "
                           "path separators", where=where,
                           hint="CAMERA_INFORMATION carries it in uint8_t[32]; ground stations name cache files after it")
    return version


def _parameter_view(s: Setting, in_cdf: set[str], where: str) -> ParameterView:
    """One setting as a definition parameter; `in_cdf` are the parameter names its exclusions and updates may name."""
    _check_parameter_name_and_type(s, where)
    _check_text(s.label, "label", where)
    description = _description(s)
    _check_text(description, "description", where)
    if s.unit is not None:
        _check_text(s.unit, "unit", where)
    values = _option_values(s, in_cdf, where) if s.options else _range_values(s, where)
    updates = tuple(u for u in s.updates if u in in_cdf and u != s.param)
    return ParameterView(name=s.param, type=s.type, default=values.default, attributes=values.attributes,
                         description=description, comment=_comment(s), updates=updates, options=values.options)


def _check_parameter_name_and_type(s: Setting, where: str) -> None:
    if not (1 <= len(s.param) <= PARAM_NAME_MAX) or not re.fullmatch(r"[A-Za-z0-9_]+", s.param):
        raise CdfError(f"PARAM_EXT name {s.param!r} must be 1-{PARAM_NAME_MAX} characters of A-Z 0-9 _",
                       where=where, hint="param_id is char[16] in PARAM_EXT_* (common.xml)")
    if s.param == "CAM_MODE":
        raise CdfError("CAM_MODE is not generated", where=where,
                       hint="the camera switches modes with MAV_CMD_SET_CAMERA_MODE; see docs/camera-definitions.md")
    if s.type not in GENERATED_TYPES:
        raise CdfError(f"type {s.type!r} is not generated", where=where,
                       hint="use uint32 for enumerations (MAVSDK mishandles uint16; QGC renders bool as true/false)")


def _option_values(s: Setting, in_cdf: set[str], where: str) -> _Values:
    """A setting with options: distinct option values, a default that is exactly one of them, exclusions."""
    hides = dict(s.hides)
    values = [_number(s, o.value, where) for o in s.options]
    if len(set(values)) != len(values):
        raise CdfError("two options have the same value", where=where,
                       hint=f"give each flag of `enums: {s.enum.id}` its own bit (0x01, 0x02, 0x04, ...)"
                       if s.flags and s.enum is not None else
                       f"{s.type} cannot tell these option values apart: use an integer `type:`")
    default = _number(s, s.default, where)
    if values.count(default) != 1:
        raise CdfError(f"default {default} is not exactly one of the options {', '.join(values)}", where=where,
                       hint="MAVSDK rejects the whole file when the default matches no option")
    unknown = set(hides) - {o.value for o in s.options}
    if unknown:
        raise CdfError(f"hides names option values {sorted(unknown)} that are not options", where=where,
                       hint=f"key `hides:` by this setting's option values: {short_list(values)}")
    options = []
    for o, value in zip(s.options, values):
        _check_text(o.name, f"option {value}", where)
        excludes = tuple(p for p in hides.get(o.value, ()) if p in in_cdf and p != s.param)
        options.append(OptionView(name=o.name, value=value, excludes=excludes))
    attributes = (("unit", s.unit),) if s.unit else ()
    return _Values(default=default, attributes=attributes, options=tuple(options))


def _range_values(s: Setting, where: str) -> _Values:
    """A setting without options: min and max (MAVSDK drops it otherwise), optional step and decimal places."""
    if s.min is None or s.max is None:
        raise CdfError("a setting without options needs min and max", where=where,
                       hint="MAVSDK drops a range parameter without both")
    if s.hides:
        raise CdfError("a range setting cannot hide others", where=where,
                       hint="the spec does not combine min/max with exclusions; give it options")
    if not float(s.min) <= float(s.default) <= float(s.max):
        raise CdfError(f"default {s.default} outside {s.min}..{s.max}", where=where,
                       hint="a bug in wiris-tools (the catalogue loader refuses this first): please report it")
    default = _number(s, s.default, where)
    attributes = [("min", _number(s, s.min, where)), ("max", _number(s, s.max, where))]
    if s.step is not None:
        if float(s.step) <= 0:
            raise CdfError(f"step {s.step} must be positive", where=where,
                           hint="give `step:` a positive value, or leave it out")
        attributes.append(("step", _number(s, s.step, where)))
    if s.decimals is not None and not s.is_integer:
        attributes.append(("decimalPlaces", str(int(s.decimals))))
    if s.unit:
        attributes.append(("unit", s.unit))
    return _Values(default=default, attributes=tuple(attributes), options=())


def _localize(camera: Camera, settings: tuple[Setting, ...], params: list[ParameterView],
              locales: tuple[Locale, ...], where: str):
    """Per locale the (original, translated) strings, in document order, with QGC's replacement hazards checked."""
    # Every text QGC's whole-file replacement must leave alone: anything that is not a description or an
    # option name (and the locale names themselves).
    protected = {camera.vendor, camera.model, str(camera.definition_version)}
    for p in params:
        protected |= {p.name, p.type, p.default, *(v for _, v in p.attributes), *p.updates}
        for o in p.options:
            protected |= {o.value, *o.excludes}
    protected |= {loc.name for loc in locales}

    # (English text, parts it is translated from); a description keeps its unit untranslated.
    texts: list[tuple[str, tuple[str, ...], str]] = []
    for s, p in zip(settings, params):
        texts.append((p.description, (s.label,), f" ({s.unit})" if s.unit else ""))
        for o in s.options:
            texts.append((o.name, _option_parts(s, o), ""))

    views, missing = [], []
    for loc in locales:
        seen: dict[str, str] = {}
        for text, parts, suffix in texts:
            if text in seen:
                continue
            translated_parts = [loc.translate(part) for part in parts]
            if any(t is None for t in translated_parts):
                missing.extend((loc.name, part) for part, t in zip(parts, translated_parts) if t is None)
                seen[text] = text
                continue
            seen[text] = " + ".join(translated_parts) + suffix   # type: ignore[arg-type]
        strings = tuple(StringView(o, t) for o, t in seen.items() if o != t)
        originals = {s.original for s in strings}
        for sv in strings:
            w = f"{loc.path or loc.name}: {sv.original!r}"
            if sv.original in protected:
                raise CdfError(f"{camera.id}: the text {sv.original!r} is also a parameter name, value, unit or "
                               "identity string, which QGroundControl's localisation would replace too",
                               where=w, hint="reword the label or option name in the catalogue table")
            if sv.original.strip("-0123456789.") == "":
                raise CdfError(f"{camera.id}: numeric text {sv.original!r} cannot be localised safely", where=w,
                               hint="remove it from the locale table, or reword that label or option name")
            if sv.translated in originals:
                raise CdfError(f"{camera.id}: translation {sv.translated!r} is itself an original string; "
                               "QGroundControl applies strings one after another and would translate it again",
                               where=w, hint="choose a different translation")
        views.append(LocaleView(name=loc.name, strings=strings))
    return tuple(views), tuple(sorted(set(missing)))


# --------------------------------------------------------------------------------------------- outputs

def definition_xml(camera: Camera, locales: Iterable[Locale] | None = None) -> bytes:
    """The camera definition file of one catalogue camera: UTF-8 XML bytes, identical on every rebuild."""
    from templates import render

    view = definition_view(camera, locales)
    text = render(TEMPLATE, vendor=view.vendor, model=view.model, version=view.version, table=view.table,
                  source=view.source, parameters=view.parameters, locales=view.locales)
    return text.encode("utf-8")


def definition_xmls(cat: Catalogue | None = None) -> dict[str, bytes]:
    """camera id -> definition bytes for every camera of the catalogue that has a definition."""
    if cat is None:
        from cdf.catalogue import catalogue

        cat = catalogue()
    locales = load_locales()
    return {cam.id: definition_xml(cam, locales) for cam in cat.cameras if cam.has_cdf}


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")


def definition_file_name(camera: Camera) -> str:
    """The published file name: vendor, model and definition version, e.g. `workswell_wiris-pro_v1.xml`.
    A new version is a new file, so a hosted definition never changes under a URI a camera reports."""
    if camera.definition_version is None:
        raise CdfError(f"{camera.id} has no definition_version", where=camera.table or camera.id,
                       hint=f"add `definition_version:` (1..65535) to the {camera.id} entry under `models:`")
    return f"{_slug(camera.vendor)}_{_slug(camera.model)}_v{camera.definition_version}.xml"


__all__ = ["Locale", "DefinitionView", "definition_view", "definition_xml", "definition_xmls",
           "definition_file_name", "load_locales"]
