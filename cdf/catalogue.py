"""The camera catalogue: every fact about a camera model, read once from cdf/tables/*.yaml.

The same values drive the camera definition XML, the emulators, the command builders and the plan
compiler's validation of settings, so a fact is written in exactly one table. A family table may
`extend` a vendor table (workswell.yaml holds the manual's enumerators, commands and setting groups)
and say what differs per model (`groups`, `overrides`, imagers).

Loading checks the tables themselves (names fit PARAM_EXT's 16 characters, defaults are legal, every
reference resolves) and raises CdfError naming the table and the entry.
"""

from __future__ import annotations

import difflib
import functools
import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, NamedTuple

from cdf.errors import CdfError, clip, shown
from cdf.paramtypes import INT_RANGES, NUMERIC_TYPES, mavsdk_range

TABLES_DIR = Path(__file__).resolve().parent / "tables"

PARAM_NAME_MAX = 16  # PARAM_EXT_* param_id is char[16] (common.xml)
# The numeric types a setting may have (no bool: QGC renders it true/false, so exclusions keyed on it never fire)
CDF_TYPES = tuple(t for t in NUMERIC_TYPES if t != "bool")
# The values MAVSDK reads of each integer type: a uint32 above 2**31-1 throws in std::stoi, so int32's top it is.
INTEGER_RANGES = {t: mavsdk_range(t) for t in INT_RANGES if t != "bool"}


@dataclass(frozen=True)
class Option:
    value: int
    key: str      # the name capture plans use
    name: str     # the label a ground station shows


@dataclass(frozen=True)
class Enumerator:
    id: str
    title: str
    options: tuple[Option, ...]
    flags: bool = False
    exclusive: tuple[tuple[str, ...], ...] = ()   # flag keys that must not be combined
    source: str = ""
    note: str = ""

    def by_key(self, key: str) -> Option | None:
        return next((o for o in self.options if o.key == key), None)

    def by_value(self, value: int) -> Option | None:
        return next((o for o in self.options if o.value == value), None)

    def combinations(self, without: Iterable[str] = ()) -> tuple[Option, ...]:
        """Every allowed non-empty OR of flags, as options (value = the OR, name = names joined)."""
        usable = [o for o in self.options if o.key not in set(without)]
        combos = []
        for n in range(1, len(usable) + 1):
            for group in itertools.combinations(usable, n):
                keys = {o.key for o in group}
                if any(set(ex) <= keys for ex in self.exclusive):
                    continue
                combos.append(Option(value=sum(o.value for o in group), key="+".join(o.key for o in group),
                                     name=" + ".join(o.name for o in group)))
        return tuple(sorted(combos, key=lambda o: o.value))


@dataclass(frozen=True)
class CommandSlot:
    """How a setting reaches the camera: a MAV_CMD param, or a message (RedEdge's PARAM_SET, DIGICAM_*)."""

    cmd: str | None = None          # MAV_CMD_* name
    param: int | None = None        # 1..7
    offset: int = 0                 # added on the wire ("Layout increased by 1")
    when: tuple[tuple[str, int], ...] = ()   # the slot carries this setting only while these settings hold these values
    keep: tuple[str, ...] = ("nan",)          # wire values meaning "leave as is": "nan" and/or "0"
    message: str | None = None      # for message-driven settings: PARAM_SET, DIGICAM_CONFIGURE
    field: str | None = None        # the message field

    def encode(self, value: float) -> float:
        return float(value) + self.offset

    def decode(self, wire: float) -> float | None:
        """The setting value a wire value asks for, or None when the wire value means keep."""
        if math.isnan(wire) or ("0" in self.keep and wire == 0):
            return None
        return wire - self.offset


@dataclass(frozen=True)
class Setting:
    key: str
    param: str
    type: str
    label: str
    default: float | int | None
    enum: Enumerator | None = None
    flags: bool = False                        # enum is a flag set; options are its combinations
    options: tuple[Option, ...] = ()            # explicit options (enum options or flag combinations)
    min: float | None = None
    max: float | None = None
    step: float | None = None
    unit: str | None = None
    decimals: int | None = None
    command: CommandSlot | None = None
    hides: tuple[tuple[int, tuple[str, ...]], ...] = ()   # option value -> PARAM names hidden
    updates: tuple[str, ...] = ()
    in_cdf: bool = True
    source: str = ""
    note: str = ""

    @property
    def is_integer(self) -> bool:
        return self.type in INTEGER_RANGES

    def option_by_key(self, key: str) -> Option | None:
        return next((o for o in self.options if o.key == key), None)

    def option_named(self, text: str) -> Option | None:
        """The option a person means by `text`: its key as a plan writes it ("manual"), or the key or the
        label a ground station shows ("Manual"), in any case. The same names work in a plan and in
        `wiris camera set`."""
        return _named(self.options, text)

    def choice_hint(self, text: str) -> str:
        """The hint for a value that names no option: the likely one, then every choice."""
        return _did_you_mean(text, self.options) + f"choose one of {', '.join(o.key for o in self.options)}"

    def check(self, value: Any) -> float | int:
        """The typed value of a plan/CLI value for this setting, or CdfError with the allowed values.

        Accepts an option key ("manual"), a list of flag keys (["radiometric_jpeg", "visible_jpeg"]),
        or a number within the options or the range.
        """
        if self.options:
            if isinstance(value, (list, tuple)) and self.flags:
                flags = self.enum.options if self.enum else ()
                named = [_named(flags, str(v)) for v in value]
                keys = [o.key for o in named if o is not None]
                bad = [str(v) for v, o in zip(value, named) if o is None]
                if bad or not keys:
                    raise CdfError(f"{self.key}: {clip(bad[0]) if bad else 'an empty list'} is not a choice",
                                   hint=(_did_you_mean(bad[0], flags) if bad else "")
                                   + f"choose one or more of {', '.join(sorted(o.key for o in flags))}")
                option = self.option_by_key("+".join(o.key for o in self.enum.options if o.key in keys))
                if option is None:
                    raise CdfError(f"{self.key}: {clip(' + '.join(keys))} cannot be combined",
                                   hint=self.enum.note or "see the camera manual")
                return option.value
            if isinstance(value, str):
                option = self.option_named(value)
                if option is None:
                    raise CdfError(f"{self.key}: {shown(value)} is not a choice", hint=self.choice_hint(value))
                return option.value
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                if any(o.value == value for o in self.options):
                    return int(value)
            raise CdfError(f"{self.key}: {shown(value)} is not a choice",
                           hint=f"choose one of {', '.join(o.key for o in self.options)}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise CdfError(f"{self.key}: expected a number{f' in {self.unit}' if self.unit else ''}, got {shown(value)}",
                           hint=self.range_text())
        if (self.min is not None and value < self.min) or (self.max is not None and value > self.max):
            raise CdfError(f"{self.key}: {shown(value)} is out of range", hint=self.range_text())
        if self.is_integer:
            if value != int(value):
                raise CdfError(f"{self.key}: {shown(value)} is not a whole number", hint=self.range_text())
            return int(value)
        return float(value)

    def range_text(self) -> str:
        if self.min is None and self.max is None:
            return "any number"
        unit = f" {self.unit}" if self.unit else ""
        step = f" in steps of {_fmt(self.step)}" if self.step else ""
        return f"allowed: {_fmt(self.min)} to {_fmt(self.max)}{unit}{step}"


@dataclass(frozen=True)
class Imager:
    id: str
    known: bool
    resolution_px: tuple[int, int] | None = None
    pixel_pitch_um: float | None = None
    sensor_mm: tuple[float, float] | None = None
    lenses_mm: tuple[float, ...] = ()
    min_interval_s: float | None = None
    # A microbolometer's thermal time constant: it integrates the scene over about this long, so motion during
    # it smears the image (the compiler's blur budget, missions.thermal.blur). None: not a thermal imager.
    time_constant_ms: float | None = None
    bands: int | None = None
    assumed: tuple[str, ...] = ()     # which of the facts above are assumptions, not sourced
    sources: tuple[tuple[str, str], ...] = ()
    note: str = ""
    time_constant_note: str = ""

    @property
    def sensor_size_mm(self) -> tuple[float, float] | None:
        """Sensor width and height: given, or pitch × resolution. For a sensor whose aspect ratio does not
        match the image (the Security's visible camera) the height follows the image's aspect ratio."""
        if self.resolution_px is None:
            return None
        w_px, h_px = self.resolution_px
        if self.sensor_mm is not None:
            width = self.sensor_mm[0]
        elif self.pixel_pitch_um is not None:
            width = w_px * self.pixel_pitch_um / 1000.0
        else:
            return None
        return width, width * h_px / w_px


@dataclass(frozen=True)
class CaptureSizes:
    """How much one photo writes to the camera's storage, by the option of the setting that chooses the files
    (a flag set: each chosen file's size adds up), from a published source. A camera without this is of
    unknown sizes: the compiler says so instead of guessing."""

    setting: str                                # the setting's key, e.g. raw_format
    mb: tuple[tuple[str, float], ...]           # option (or flag) key -> megabytes (10^6 bytes) per photo
    source: str

    def per_photo_mb(self, setting: Setting, value: float | int) -> float | None:
        """Megabytes one photo writes with `setting` at wire value `value`; None when a chosen file's size is
        not in the table."""
        sizes = dict(self.mb)
        if setting.flags and setting.enum is not None:
            keys = [o.key for o in setting.enum.options if int(value) & o.value]
        else:
            option = next((o for o in setting.options if o.value == value), None)
            keys = [option.key] if option is not None else []
        if not keys or any(k not in sizes for k in keys):
            return None
        return sum(sizes[k] for k in keys)


@dataclass(frozen=True)
class Camera:
    id: str
    family: str
    vendor: str
    model: str
    protocol: str                      # "workswell-mavlink" or "rededge-serial"
    definition_version: int | None
    camera_protocol: bool              # the manual states camera-protocol (CDF/PARAM_EXT) support
    has_cdf: bool
    component_ids: tuple[int, ...]
    default_component_id: int
    mavlink_version: int
    baud: int
    capabilities: tuple[str, ...]
    settings: tuple[Setting, ...]
    enums: tuple[Enumerator, ...]
    imagers: tuple[Imager, ...]
    commands: tuple[tuple[str, dict], ...] = ()
    assumed: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    source: str = ""
    table: str = ""
    extra: tuple[tuple[str, Any], ...] = field(default=(), compare=False)
    capture_sizes: CaptureSizes | None = None      # None: no published image sizes

    def capture_formats(self, values: Any) -> tuple[str, float | None]:
        """The files a photo writes with the settings `values` (key -> wire value; a setting left out holds its
        default), as "radiometric_jpeg + visible_jpeg", and their megabytes per photo (None: not known)."""
        chooser = self.capture_sizes.setting if self.capture_sizes else next(
            (s.key for s in self.settings if s.key == "capture"), None)
        s = self.setting(chooser) if chooser else None
        if s is None:
            return "", None
        value = dict(values).get(s.key, s.default)
        if value is None:
            return "", None
        if s.flags and s.enum is not None:
            text = " + ".join(o.key for o in s.enum.options if int(value) & o.value)
        else:
            text = str(self.option_key(s.key, value))
        return text, self.capture_sizes.per_photo_mb(s, value) if self.capture_sizes else None

    def setting(self, key: str) -> Setting | None:
        return next((s for s in self.settings if s.key == key), None)

    def setting_by_param(self, param: str) -> Setting | None:
        return next((s for s in self.settings if s.param == param), None)

    def setting_named(self, name: str) -> Setting | None:
        """The setting a person means by `name`: its plan name ("range_mode") or its PARAM_EXT name as the
        camera definition and `wiris camera settings` show it ("RANGE_MODE"), in any case."""
        exact = self.setting(name) or self.setting_by_param(name)
        if exact is not None:
            return exact
        folded = name.strip().casefold()
        return next((s for s in self.settings if folded in (s.key.casefold(), s.param.casefold())), None)

    def setting_hint(self, name: str) -> str:
        """The hint for a name that is no setting of this camera: the likely one, then every plan name."""
        names = {s.key: s.key for s in self.settings} | {s.param.casefold(): s.key for s in self.settings}
        close = difflib.get_close_matches(name.strip().casefold(), list(names), n=1)
        keys = ", ".join(s.key for s in self.settings)
        return (f"did you mean {names[close[0]]!r}? " if close else "") + f"settings: {keys}"

    def option_key(self, key: str, value: Any) -> Any:
        """How a plan writes `value` of setting `key`: its option's key when the setting has one for it."""
        s = self.setting(key)
        option = s.enum.by_value(value) if s is not None and s.enum else None
        return option.key if option is not None else value

    def imager(self, imager_id: str) -> Imager | None:
        return next((i for i in self.imagers if i.id == imager_id), None)

    def enum(self, enum_id: str) -> Enumerator | None:
        return next((e for e in self.enums if e.id == enum_id), None)

    @property
    def cdf_settings(self) -> tuple[Setting, ...]:
        return tuple(s for s in self.settings if s.in_cdf)

    def command_info(self, name: str) -> dict | None:
        return dict(self.commands).get(name)


@dataclass(frozen=True)
class Catalogue:
    cameras: tuple[Camera, ...]

    def get(self, camera_id: str) -> Camera:
        for cam in self.cameras:
            if cam.id == camera_id:
                return cam
        import difflib

        close = difflib.get_close_matches(camera_id, [c.id for c in self.cameras], n=1)
        hint = f"did you mean {close[0]!r}?" if close else "see `wiris cdf models`"
        raise CdfError(f"unknown camera {camera_id!r}", hint=hint)

    @property
    def ids(self) -> tuple[str, ...]:
        return tuple(c.id for c in self.cameras)

    def find_model(self, vendor: str, model: str) -> Camera | None:
        """The catalogue camera a CAMERA_INFORMATION's vendor and model strings name."""
        for cam in self.cameras:
            if cam.vendor.lower() == vendor.strip().lower() and cam.model.lower() == model.strip().lower():
                return cam
        return None


def _named(options: Iterable[Option], text: str) -> Option | None:
    """The option whose key is `text`, else whose key or label is `text` in any case."""
    options = tuple(options)
    exact = next((o for o in options if o.key == text), None)
    if exact is not None:
        return exact
    folded = text.strip().casefold()
    return next((o for o in options if folded in (o.key.casefold(), o.name.casefold())), None)


def _did_you_mean(text: str, options: Iterable[Option]) -> str:
    """"did you mean 'manual'? " for a near miss of an option's key or label, else ""."""
    names = {}
    for o in options:
        names.setdefault(o.key.casefold(), o.key)
        names.setdefault(o.name.casefold(), o.key)
    close = difflib.get_close_matches(text.strip().casefold(), list(names), n=1)
    return f"did you mean {names[close[0]]!r}? " if close else ""


def _fmt(v: float | None) -> str:
    if v is None:
        return "?"
    return str(int(v)) if float(v).is_integer() else f"{v:g}"


def _name_hint(name: Any, known: Iterable[str], rule: str, aliases: dict[str, str] | None = None) -> str:
    """The hint for a table entry naming something that does not exist: the likely name ('did you mean'),
    else the names it may be when they are few, else the rule alone. `aliases` maps names of the wrong
    kind (a setting key where a PARAM_EXT name belongs) to the right one."""
    names = sorted({str(k) for k in known})
    close = (aliases or {}).get(str(name)) or next(iter(difflib.get_close_matches(str(name), names, n=1)), None)
    if close:
        return f"did you mean {close!r}? ({rule})"
    if not names:
        return f"{rule}; this table defines none"
    listed = ", ".join(names)
    return f"{rule}: {listed}" if len(listed) <= 60 else f"{rule}; check the spelling"


def short_list(texts: Iterable[str], most: int = 8) -> str:
    """The first `most` texts, comma-separated, and "..." when there are more (values listed in a hint)."""
    shown = list(texts)
    return ", ".join(shown[:most]) + (", ..." if len(shown) > most else "")


def _read_yaml(path: Path) -> dict:
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when present: 10x faster, same result
    try:
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=loader)
    except FileNotFoundError:
        raise CdfError("no such catalogue table", where=str(path),
                       hint="`extends:` names a table of the same directory, without .yaml (e.g. workswell)") from None
    except (OSError, UnicodeDecodeError) as err:
        raise CdfError(f"cannot read catalogue table: {getattr(err, 'strerror', None) or err}", where=str(path),
                       hint="tables are UTF-8 text files the user may read") from None
    except yaml.YAMLError as err:
        raise CdfError(f"cannot parse catalogue table: {err}", where=str(path),
                       hint="fix the YAML at the line and column it names (indentation, quotes, colons)") from None
    if not isinstance(data, dict):
        raise CdfError("a catalogue table must be a mapping", where=str(path),
                       hint="write top-level `key: value` entries, e.g. `extends:`, `models:`, `settings:`")
    return data


def _enums(raw: dict, where: str) -> dict[str, Enumerator]:
    out = {}
    for eid, e in (raw or {}).items():
        opts = tuple(Option(value=int(o["value"]), key=str(o["key"]), name=str(o["name"])) for o in e["options"])
        if len({o.value for o in opts}) != len(opts) or len({o.key for o in opts}) != len(opts):
            raise CdfError(f"enumerator {eid}: duplicate value or key", where=where,
                           hint=f"give each option under `enums: {eid}: options:` its own `value:` and `key:`")
        out[eid] = Enumerator(id=eid, title=e.get("title", eid), options=opts, flags=bool(e.get("flags")),
                              exclusive=tuple(tuple(x) for x in e.get("exclusive", ())),
                              source=e.get("source", ""), note=e.get("note", ""))
    return out


def _setting(raw: dict, enums: dict[str, Enumerator], where: str) -> Setting:
    raw = dict(raw)
    without = raw.pop("without", ())
    key = raw["key"]
    enum = None
    options: tuple[Option, ...] = ()
    flags = False
    if "enum" in raw:
        enum = enums.get(raw["enum"])
        if enum is None:
            raise CdfError(f"setting {key}: unknown enumerator {raw['enum']!r}", where=where,
                           hint=_name_hint(raw["enum"], enums, "`enum:` names a key of `enums:`"))
        options = tuple(o for o in enum.options if o.key not in set(without))
    elif "flags" in raw:
        enum = enums.get(raw["flags"])
        if enum is None or not enum.flags:
            hint = (f"add `flags: true` to `enums: {enum.id}`, or write `enum: {enum.id}` for a single choice"
                    if enum is not None else
                    _name_hint(raw["flags"], [e.id for e in enums.values() if e.flags],
                               "`flags:` names a key of `enums:` that has `flags: true`"))
            raise CdfError(f"setting {key}: {raw['flags']!r} is not a flag enumerator", where=where, hint=hint)
        flags = True
        options = enum.combinations(without)
    cmd = raw.get("command")
    slot = None
    if cmd:
        slot = CommandSlot(cmd=cmd.get("cmd"), param=cmd.get("param"), offset=int(cmd.get("offset", 0)),
                           when=tuple((k, int(v)) for k, v in (cmd.get("when") or {}).items()),
                           keep=tuple(str(k) for k in cmd.get("keep", ["nan"])),
                           message=cmd.get("message"), field=cmd.get("field"))
    hides = tuple((int(v), tuple(names)) for v, names in (raw.get("hides") or {}).items())
    return Setting(
        key=key, param=raw["param"], type=raw["type"], label=raw["label"], default=raw.get("default"),
        enum=enum, flags=flags, options=options, min=raw.get("min"), max=raw.get("max"), step=raw.get("step"),
        unit=raw.get("unit"), decimals=raw.get("decimals"), command=slot, hides=hides,
        updates=tuple(raw.get("updates", ())), in_cdf=bool(raw.get("cdf", True)) and raw.get("default") is not None,
        source=raw.get("source", ""), note=raw.get("note", ""),
    )


def _imagers(raw: dict) -> tuple[Imager, ...]:
    out = []
    for iid, im in (raw or {}).items():
        known = im.get("status") != "unknown"
        assumed = tuple(k.removesuffix("_status") for k, v in im.items() if k.endswith("_status") and v == "assumed")
        sources = tuple((k.removesuffix("_source"), v) for k, v in im.items() if k.endswith("_source"))
        res = im.get("resolution_px")
        sensor = im.get("sensor_mm")
        out.append(Imager(
            id=iid, known=known, resolution_px=tuple(res) if res else None,
            pixel_pitch_um=im.get("pixel_pitch_um"), sensor_mm=tuple(sensor) if sensor else None,
            lenses_mm=tuple(float(x) for x in im.get("lenses_mm", ())), min_interval_s=im.get("min_interval_s"),
            time_constant_ms=im.get("time_constant_ms"), bands=im.get("bands"), assumed=assumed, sources=sources,
            note=" ".join(str(im[k]) for k in im if k == "note" or (k.endswith("_note") and k != "time_constant_note")),
            time_constant_note=str(im.get("time_constant_note", "")),
        ))
    return tuple(out)


def _check_setting(s: Setting, where: str) -> None:
    if not (1 <= len(s.param) <= PARAM_NAME_MAX) or not s.param.isascii():
        raise CdfError(f"setting {s.key}: PARAM_EXT name {s.param!r} must be 1–{PARAM_NAME_MAX} ASCII characters",
                       where=where,
                       hint=(f"shorten `param:` to at most {PARAM_NAME_MAX} characters" if len(s.param) > PARAM_NAME_MAX
                             else "write `param:` in ASCII letters, digits and _")
                       + " (PARAM_EXT param_id is char[16])")
    if s.type not in CDF_TYPES:
        raise CdfError(f"setting {s.key}: type {s.type!r} is not a definition type", where=where,
                       hint=f"set `type:` to one of {', '.join(CDF_TYPES)}")
    if s.default is None:
        return
    if s.options:
        if not any(o.value == s.default for o in s.options):
            left_out = s.enum.by_value(s.default) if s.enum is not None else None
            hint = f"set `default:` to one of the option values {short_list(_fmt(o.value) for o in s.options)}"
            if left_out is not None:
                hint = f"`without:` leaves out option {left_out.key!r}: keep it, or {hint}"
            raise CdfError(f"setting {s.key}: default {s.default} is not among its options", where=where, hint=hint)
    else:
        if s.min is None or s.max is None:
            raise CdfError(f"setting {s.key}: needs options or min and max (MAVSDK drops it otherwise)", where=where,
                           hint="add `min:` and `max:`, or give it options with `enum:` or `flags:`")
        if not (s.min <= s.default <= s.max):
            raise CdfError(f"setting {s.key}: default {s.default} outside {s.min}..{s.max}", where=where,
                           hint=f"set `default:` between {_fmt(s.min)} and {_fmt(s.max)}, or widen `min:`/`max:`")
    if s.is_integer:
        lo, hi = INTEGER_RANGES[s.type]
        values = [o.value for o in s.options] + [v for v in (s.min, s.max, s.default) if v is not None]
        if any(int(v) != v or not lo <= v <= hi for v in values):
            raise CdfError(f"setting {s.key}: a value does not fit {s.type}", where=where,
                           hint=f"{s.type} takes whole numbers {lo}..{hi}: fix `default:`, `min:`, `max:` or the "
                                "options, or change `type:`")


def _load_table(path: Path, read: Callable[[Path], dict] = _read_yaml) -> list[Camera]:
    """The cameras of one family table; an entry without a key the loader needs, or of the wrong kind, is a
    CdfError naming the table (the named checks below say more where they apply)."""
    try:
        return _cameras_of_table(path, read)
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as err:
        what = f"missing key {err}" if isinstance(err, KeyError) else f"{type(err).__name__}: {err}"
        raise CdfError(f"a table entry is incomplete or of the wrong kind ({what})", where=path.name,
                       hint="compare the entry with the same one in wiris-pro.yaml (enums need options: with "
                            "value, key, name; settings need key: and param:)") from None


class _Table(NamedTuple):
    """A family table and the vendor base table it `extends:` ({} if none); `merged` lets the family's keys win."""

    raw: dict
    base: dict
    merged: dict


def _cameras_of_table(path: Path, read: Callable[[Path], dict]) -> list[Camera]:
    where = path.name
    table = _read_table(path, read)
    enums = _enums({**(table.base.get("enums") or {}), **(table.raw.get("enums") or {})}, where)
    settings = _table_settings(table, enums, where)
    _check_unique_settings(settings, where)
    commands = table.merged.get("commands") or {}
    _check_setting_references(settings, commands, where)
    notes = tuple(str(v) for k, v in table.merged.items() if k.endswith("_note") and isinstance(v, str))
    return [_camera(m, table.merged, settings, enums, commands, notes, path.name) for m in table.merged["models"]]


def _read_table(path: Path, read: Callable[[Path], dict]) -> _Table:
    raw = read(path)
    base: dict = {}
    if "extends" in raw:
        base = read(path.parent / f"{raw['extends']}.yaml")
    return _Table(raw=raw, base=base, merged={**base, **{k: v for k, v in raw.items() if k != "extends"}})


def _table_settings(table: _Table, enums: dict[str, Enumerator], where: str) -> tuple[Setting, ...]:
    """The base table's `groups:` the family names, then its own `settings:`, each with its `overrides:`."""
    base, raw = table.base, table.raw
    overrides = table.merged.get("overrides") or {}
    raw_settings: list[dict] = []
    for group in table.merged.get("groups", []):
        if group not in (base.get("groups") or {}):
            hint = (_name_hint(group, base["groups"], f"`groups:` names groups of {raw['extends']}.yaml")
                    if base.get("groups") else
                    "`groups:` needs `extends:` naming a vendor table that defines `groups:`")
            raise CdfError(f"unknown setting group {group!r}", where=where, hint=hint)
        raw_settings.extend(base["groups"][group])
    raw_settings.extend(raw.get("settings", []))
    settings = tuple(_setting({**s, **overrides.get(s["key"], {})}, enums, where) for s in raw_settings)
    unknown_overrides = set(overrides) - {s.key for s in settings}
    if unknown_overrides:
        raise CdfError(f"overrides name unknown settings: {', '.join(sorted(unknown_overrides))}", where=where,
                       hint=_name_hint(sorted(unknown_overrides)[0], [s.key for s in settings],
                                       "`overrides:` is keyed by the `key:` of a setting of this model"))
    return settings


def _check_unique_settings(settings: tuple[Setting, ...], where: str) -> None:
    params = [s.param for s in settings]
    keys = [s.key for s in settings]
    for names, what, entry in ((params, "PARAM_EXT name", "param"), (keys, "setting key", "key")):
        dupes = {n for n in names if names.count(n) > 1}
        if dupes:
            raise CdfError(f"duplicate {what}: {', '.join(sorted(dupes))}", where=where,
                           hint=f"give each setting its own `{entry}:` (settings come from `settings:` and `groups:`)")


def _check_setting_references(settings: tuple[Setting, ...], commands: dict, where: str) -> None:
    """Each setting on its own, then what it names: hidden parameters, its command, the settings of its `when:`."""
    params = [s.param for s in settings]
    keys = [s.key for s in settings]
    for s in settings:
        _check_setting(s, where)
        for _, hidden in s.hides:
            missing = [h for h in hidden if h not in params]
            if missing:
                raise CdfError(f"setting {s.key}: hides unknown {', '.join(missing)}", where=where,
                               hint=_name_hint(missing[0], params, "`hides:` lists the `param:` names of settings",
                                               aliases={o.key: o.param for o in settings}))
        if s.command and s.command.cmd and s.command.cmd not in commands:
            raise CdfError(f"setting {s.key}: command {s.command.cmd} is not in the commands table", where=where,
                           hint=_name_hint(s.command.cmd, commands, "`command: cmd:` names a key of `commands:`"))
        if s.command:
            for k, _ in s.command.when:
                if k not in keys:
                    raise CdfError(f"setting {s.key}: 'when' names unknown setting {k}", where=where,
                                   hint=_name_hint(k, keys, "`when:` is keyed by the `key:` of a setting",
                                                   aliases={o.param: o.key for o in settings}))


def _camera(m: dict, merged: dict, settings: tuple[Setting, ...], enums: dict[str, Enumerator], commands: dict,
            notes: tuple[str, ...], table: str) -> Camera:
    """One `models:` entry `m` of a family table (`merged` over its vendor base table)."""
    protocol = merged.get("protocol", "workswell-mavlink")
    has_cdf = bool(m.get("cdf", True)) and protocol == "workswell-mavlink"
    link = merged.get("link") or {}
    return Camera(
        id=m["id"], family=merged.get("family", m["id"]), vendor=merged["vendor"], model=m["model"],
        protocol=protocol, definition_version=m.get("definition_version"),
        camera_protocol=bool(m.get("camera_protocol", False)), has_cdf=has_cdf,
        component_ids=tuple(merged["component_ids"]), default_component_id=int(merged["default_component_id"]),
        mavlink_version=int(link.get("mavlink", 2)), baud=int(link.get("baud", 57600)),
        capabilities=tuple(merged.get("capabilities", ())), settings=settings,
        enums=tuple(enums.values()), imagers=_imagers(merged.get("imagers")),
        commands=tuple(commands.items()),
        assumed=tuple(k.removesuffix("_status") for k, v in m.items() if k.endswith("_status") and v == "assumed"),
        notes=notes + tuple(str(v) for k, v in m.items() if k.endswith("_note")),
        source=merged.get("source", ""), table=table,
        extra=tuple((k, merged[k]) for k in ("heartbeat", "adopts_sender_system_id", "capabilities_note")
                    if k in merged),
        capture_sizes=_capture_sizes(merged.get("capture_sizes"), settings, table),
    )


def _capture_sizes(raw: Any, settings: tuple[Setting, ...], where: str) -> CaptureSizes | None:
    """A table's `capture_sizes:`, checked: it names a setting with options, each size keyed by one of them."""
    if raw is None:
        return None
    s = next((x for x in settings if x.key == raw.get("setting")), None)
    if s is None or not (s.options or s.enum):
        raise CdfError(f"capture_sizes: setting {raw.get('setting')!r} is no setting with options", where=where,
                       hint=_name_hint(raw.get("setting"), [x.key for x in settings if x.options],
                                       "`capture_sizes: setting:` names the `key:` of the setting choosing the files"))
    keys = {o.key for o in (s.enum.options if s.flags and s.enum else s.options)}
    mb = {str(k): float(v) for k, v in (raw.get("mb") or {}).items()}
    bad = sorted(set(mb) - keys)
    if bad or not mb or any(not (math.isfinite(v) and v > 0) for v in mb.values()):
        raise CdfError(f"capture_sizes of {s.key}: {'unknown option ' + bad[0] if bad else 'a size is not positive'}",
                       where=where, hint=f"`mb:` maps options of {s.key} ({', '.join(sorted(keys))}) to megabytes "
                                         "per photo, e.g. {tiff: 12.5}")
    if not str(raw.get("source") or "").strip():
        raise CdfError(f"capture_sizes of {s.key} has no source", where=where,
                       hint="say where the sizes are published (`source:`); without one leave the sizes out")
    return CaptureSizes(s.key, tuple(mb.items()), str(raw["source"]))


def load_catalogue(tables_dir: Path | None = None) -> Catalogue:
    """Read and check every family table in `tables_dir` (vendor base tables are those without `models`)."""
    directory = tables_dir or TABLES_DIR
    read = functools.lru_cache(maxsize=None)(_read_yaml)   # the vendor base table is shared by every family
    cameras: list[Camera] = []
    for path in sorted(directory.glob("*.yaml")):
        if "models" not in read(path):
            continue
        cameras.extend(_load_table(path, read))
    ids = [c.id for c in cameras]
    dupes = {i for i in ids if ids.count(i) > 1}
    if dupes:
        tables = sorted({c.table for c in cameras if c.id in dupes})
        raise CdfError(f"camera id used twice: {', '.join(sorted(dupes))}", where=str(directory),
                       hint=f"give each `models:` entry its own `id:` (see {', '.join(tables)})")
    return Catalogue(cameras=tuple(cameras))


@functools.lru_cache(maxsize=1)
def catalogue() -> Catalogue:
    """The bundled catalogue, loaded once per process (the tables are immutable data)."""
    return load_catalogue()
