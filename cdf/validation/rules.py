"""The rule table: every check the CDF validator makes, with its severity in each profile.

Ids are stable: a rule is never renumbered or reused; a retired rule keeps its row with `retired=True`.
Groups: CDF0xx loading and safety, CDF1xx structure and values, CDF2xx cross-references and semantics,
CDF3xx checks against what the camera reports (CAMERA_INFORMATION, PARAM_EXT types) when the caller
supplies it. `ref` points at the reference (camera-definition-files.md: §C rule numbers, §3 QGC, §4 MAVSDK,
§D measured facts). cdf/schema/RULES.md is generated from this table (`python -m cdf.validation.rules`)
and a test compares the two.

Profiles (spec/cli.md): `qgc` = what QGroundControl's parser needs; `mavsdk` = what MAVSDK needs without
dropping anything (a parameter it silently skips is an error); `strict` = both, plus MAVProxy's parser's
rejections and the interoperability warnings. Severity None = not reported in that profile.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal, NamedTuple

Severity = Literal["error", "warning", "info"]
PROFILES = ("qgc", "mavsdk", "strict")
E, W, I, N = "error", "warning", "info", None
RANK = {None: 0, "info": 1, "warning": 2, "error": 3}


@dataclass(frozen=True)
class Rule:
    id: str
    name: str
    qgc: Severity | None
    mavsdk: Severity | None
    strict: Severity | None
    checks: str
    why: str
    ref: str
    retired: bool = False

    def severity(self, profile: str) -> Severity | None:
        if profile not in PROFILES:
            raise ValueError(f"unknown profile {profile!r}; choose one of {', '.join(PROFILES)}")
        return getattr(self, profile)


RULES: tuple[Rule, ...] = (
    # --- loading and safety --------------------------------------------------------------------------
    Rule("CDF001", "source-unreadable", E, E, E,
         "The file or URL could be read (exists, HTTP 200, answers within the timeout, redirects only to http(s)).",
         "Nothing can be validated; a GCS would show a camera without settings. (Reported by the CLI for a CdfError.)",
         "§1.4, §3.5, §4.5"),
    Rule("CDF002", "too-large", E, E, E,
         "At most 4 MiB on the wire and 4 MiB after xz inflation.",
         "MAVProxy refuses bigger files; real CDFs are under 64 KB, so more is an attack or a mistake.",
         "§C32, MAVProxy MAX_DEFINITION_SIZE"),
    Rule("CDF003", "xz-invalid", E, E, E,
         "An xz file (detected by magic number) is one complete, valid stream.",
         "GCS inflaters (MAVSDK InflateLZMA, QGC QGCCompression) fail on truncated or concatenated streams.",
         "§C32, camera_def.md §File Compression"),
    Rule("CDF004", "not-well-formed", E, E, E,
         "The bytes are well-formed XML in a valid encoding (UTF-8 by default).",
         "QGC (QDom), MAVSDK (tinyxml2) and MAVProxy all reject the whole file.",
         "§3.2 (1), §4.2, reference B.2"),
    Rule("CDF005", "dtd-present", W, W, E,
         "No <!DOCTYPE>, no entity declarations. Entities are never expanded here.",
         "MAVProxy refuses any DTD (defusedxml forbid_dtd); DTDs enable billion-laughs and external-entity attacks.",
         "§C33, §D"),
    Rule("CDF006", "too-complex", E, E, E,
         "Elements nest at most 64 deep and the file has at most 5000 elements (real files: 8 deep, under 900).",
         "Deep nesting and huge sibling lists are resource attacks on recursive parsers and schema validators.",
         "DESIGN.md (untrusted input)"),
    Rule("CDF007", "encoding", I, I, W,
         "The XML declaration exists and declares UTF-8.",
         "The examples declare UTF-8; GCSs decode descriptions as UTF-8.",
         "§C33"),
    Rule("CDF008", "not-utf8", W, E, E,
         "The bytes are UTF-8 (a UTF-8 byte-order mark is fine): not UTF-16 or UTF-32.",
         "MAVSDK's tinyxml2 reads bytes as UTF-8 only and rejects a UTF-16 file at line 1 (measured on "
         "tests/data/cdf/e90_camera_utf16.xml); MAVProxy detects the encoding and loads it, so does QGC's QDom.",
         "§4.2, tests/data/cdf/README.md"),
    Rule("CDF009", "encoding-declared-wrong", E, W, E,
         "The encoding the XML declaration names is the one the bytes are in (UTF-8 bytes declared UTF-16).",
         "MAVProxy (expat) believes the declaration and rejects the file, and so does QGC's QDom (code reading, "
         "not run); MAVSDK's tinyxml2 ignores it and loads the UTF-8 (measured). The rules run on the UTF-8.",
         "§4.2, bench/cdf_mutants.py"),
    # --- structure and values (mostly found by mavlinkcamera.xsd) --------------------------------------
    Rule("CDF100", "schema", W, W, E,
         "Any other violation of mavlinkcamera.xsd (structure, attribute lexical types).",
         "The file deviates from the documented shape; behaviour then differs between parsers.",
         "cdf/schema/mavlinkcamera.xsd"),
    Rule("CDF101", "root-element", W, E, E,
         "The root element is <mavlinkcamera>.",
         "MAVSDK and MAVProxy reject any other root; QGC does not check it.",
         "§C1, §4.2"),
    Rule("CDF102", "section-placement", W, E, E,
         "<definition> and <parameters> are direct children of the root.",
         "MAVSDK and MAVProxy read direct children only; QGC finds them anywhere.",
         "§C1, §4.2"),
    Rule("CDF103", "section-missing", E, E, E,
         "A <definition> and a <parameters> element exist.",
         "Both GCS parsers reject a file without them.",
         "§C1, §3.2 (2, 3), §4.2"),
    Rule("CDF104", "model-vendor-missing", E, E, E,
         "<definition> has <model> and <vendor> direct children.",
         "QGC (_loadConstants) and MAVSDK (parse_xml) reject the file.",
         "§C2, §3.2 (2)"),
    Rule("CDF105", "empty-text", W, E, E,
         "<model>, <vendor>, <description>, <update> and <exclude> have non-empty text.",
         "MAVSDK assigns tinyxml2's nullptr for empty text and crashes the whole process (measured).",
         "§C2, §C9, §C21, §D"),
    Rule("CDF106", "version-missing", E, I, E,
         "<definition> has a version attribute.",
         "QGC rejects the file without it; MAVSDK ignores it.",
         "§C2, §3.2 (2)"),
    Rule("CDF107", "version-value", W, I, W,
         "definition@version is an integer 0-65535 (CAMERA_INFORMATION.cam_definition_version is uint16).",
         "QGC reads it with toInt(): anything else becomes 0 and caching breaks.",
         "§C2, common.xml CAMERA_INFORMATION"),
    Rule("CDF108", "no-parameters", E, W, E,
         "At least one <parameter>.",
         "QGC rejects a file where no parameter loads; MAVSDK loads an empty one (measured).",
         "§C5, §3.2 (8), §D"),
    Rule("CDF109", "name-or-type-missing", E, E, E,
         "Every <parameter> has name and type attributes.",
         "Both GCS parsers reject the whole file in a pre-pass.",
         "§C6, §3.2 (4, 5), §4.2"),
    Rule("CDF110", "type-unknown", E, E, E,
         "type is one of bool, uint8, int8, uint16, int16, uint32, int32, uint64, int64, float, double, custom (or string).",
         "An unknown type makes QGC and MAVSDK reject the whole file.",
         "§C8, §3.2 (5), §4.2"),
    Rule("CDF111", "type-case", I, E, E,
         "type is written in lower case.",
         "MAVSDK compares case-sensitively and rejects the file; QGC and MAVProxy accept any case.",
         "§C8, §4.2"),
    Rule("CDF112", "type-string", W, E, E,
         "No type=\"string\" (not in the spec).",
         "MAVSDK skips the parameter and MAVProxy rejects the whole file (measured); QGC accepts it.",
         "§C8, §1.3, §4.3, §D"),
    Rule("CDF113", "type-custom", I, E, E,
         "No type=\"custom\".",
         "MAVSDK silently skips custom parameters (measured: 'Ignoring custom params'); QGC shows no control for them.",
         "§1.3, §4.3"),
    Rule("CDF114", "description-missing", E, E, E,
         "Every parameter has a <description> direct child.",
         "QGC and MAVSDK reject the whole file.",
         "§C9, §3.2 (6), §4.2"),
    Rule("CDF115", "uint16", W, W, W,
         "No uint16 parameters.",
         "MAVSDK's camera plugin logs 'Unknown type for param' for uint16 and never tracks value changes (measured).",
         "§D"),
    Rule("CDF116", "name-invalid", E, E, E,
         "name is at most 16 bytes long (UTF-8).",
         "PARAM_EXT param_id is char[16]: QGC truncates, MAVSDK never requests a longer name (it drops the "
         "parameter, measured), MAVProxy rejects it.",
         "§C7, common.xml PARAM_EXT_*"),
    Rule("CDF117", "name-duplicate", E, W, E,
         "Parameter names are unique.",
         "QGC drops the second definition, MAVProxy rejects the file, MAVSDK loads it and keeps one of them "
         "(measured in bench/cdf_mutants.py: no rejection, no dropped name).",
         "§C7, §3.3"),
    Rule("CDF118", "name-style", I, I, I,
         "Names use [A-Z0-9_] (CAM_ prefix recommended).",
         "Convention of every public camera file; lower-case hyphenated names (Dronecode) work but stand out.",
         "§C7"),
    Rule("CDF119", "default-missing", I, E, E,
         "Every non-custom parameter has a default attribute.",
         "MAVSDK silently skips the parameter ('Default missing', measured); the spec says 'minimally ... default'.",
         "§C10, §4.3"),
    Rule("CDF120", "value-lexical", W, E, E,
         "default, min, max, step and option/roption values parse as the declared type and fit its range "
         "(integers as plain decimal, bool 0/1, finite floats).",
         "MAVSDK's std::stoi family throws (process crash) or silently truncates; QGC warns and ignores; "
         "MAVProxy rejects the file.",
         "§C11, §C15, §4.2, §D"),
    Rule("CDF121", "int-over-int32", I, E, E,
         "Values of 8/16/32-bit integer types and bool are at most 2147483647.",
         "MAVSDK reads them with std::stoi: a uint32 above 2^31-1 throws out_of_range and crashes (measured).",
         "§C12, §D"),
    Rule("CDF122", "option-outside-options", W, E, E,
         "<option> elements sit inside <options>.",
         "MAVSDK reads direct children only and does not see them (the parameter loses its options or is skipped).",
         "§C13, §4.3"),
    Rule("CDF123", "name-value-missing", E, E, E,
         "Every <option> and <roption> has name and value; every <parameterrange> has parameter.",
         "QGC rejects the file; MAVSDK skips the parameter.",
         "§C13, §C23, §3.2 (7), §4.3"),
    Rule("CDF124", "option-duplicate", W, W, E,
         "Option values are unique within a parameter.",
         "Two options with one value are ambiguous; if the default hits both, MAVSDK rejects the file.",
         "§C13, §4.2 find_default"),
    Rule("CDF125", "default-not-an-option", W, E, E,
         "When a parameter has options, its default equals exactly one option value (compared as typed values).",
         "MAVSDK rejects the whole file ('No default found'; measured on the devguide example, RealSense, STorM32).",
         "§C14, §4.2"),
    Rule("CDF126", "bool-trigger", W, W, W,
         "No exclusions or parameter ranges keyed on a bool option (use uint8 with explicit options).",
         "QGC compares option text with rawValueString(), which renders bools as true/false: the rule never fires.",
         "§C15, §3.4"),
    Rule("CDF127", "range-missing", I, E, E,
         "A non-bool parameter without options has both min and max.",
         "MAVSDK silently skips it ('Range not found', measured on MicaSense and Yuneec files).",
         "§C16, §4.3"),
    Rule("CDF128", "range-invalid", W, W, E,
         "min <= max and step > 0.",
         "MAVProxy rejects the file; the control is unusable elsewhere.",
         "§C17, MAVProxy Parameter.__init__"),
    Rule("CDF129", "range-semantics", W, W, W,
         "min <= default <= max, default on the step grid, min/max/step not combined with options, exclusions or ranges.",
         "The spec says a range cannot be combined with exclusions or option ranges; an off-grid default cannot be set back.",
         "§C17, camera_def.md §Param Ranges"),
    Rule("CDF130", "flag-value", W, W, W,
         "control, readonly and writeonly are exactly \"0\" or \"1\".",
         "QGC treats anything but \"0\" as true, MAVSDK only \"1\": control=\"false\" is visible in QGC.",
         "§C18, §3.4, §4.4"),
    Rule("CDF131", "readonly-writeonly", W, E, E,
         "Not readonly=\"1\" and writeonly=\"1\" together.",
         "MAVSDK rejects the whole file; QGC logs 'cannot be both'.",
         "§C19, §4.2, §3.3"),
    Rule("CDF132", "custom-control", I, I, I,
         "custom and string parameters carry control=\"0\".",
         "QGC and MAVSDK force control off for custom; say so explicitly.",
         "§C20"),
    Rule("CDF133", "type-qgc-only", I, E, E,
         "No QGC-only types (elapsedSeconds).",
         "QGC's FactMetaData accepts ElapsedSeconds; MAVSDK rejects the file (unknown type), MAVProxy rejects it too.",
         "§3.2 (5), §4.2"),
    Rule("CDF134", "name-charset", E, W, E,
         "A name of at most 16 bytes is 1-16 printable ASCII characters (not empty, no accents or controls).",
         "MAVProxy rejects the file and QGC matches names by text; MAVSDK loads the file and answers the "
         "parameter (measured in bench/cdf_mutants.py).",
         "§C7, MAVProxy Parameter.__init__"),
    # --- cross-references and semantics ----------------------------------------------------------------
    Rule("CDF200", "misplaced-element", W, W, E,
         "<exclusions> is a direct child of <option>, <updates> of <parameter>, <parameterranges> of <option>; "
         "no nested <exclusions>.",
         "MAVSDK and MAVProxy read direct children only: they load the file with every parameter and silently "
         "lose the misplaced element (measured on tests/data/cdf/e90_camera_exclusions_beside_options.xml); "
         "QGC searches recursively.",
         "§C21, §C22, §4.3"),
    Rule("CDF201", "exclude-unknown", W, W, W,
         "Each <exclude> names an existing parameter.",
         "A typo hides nothing; Dronecode and MAVSDK's uvc files exclude names that do not exist.",
         "§C21"),
    Rule("CDF202", "update-unknown", E, W, E,
         "Each <update> names an existing parameter other than itself.",
         "QGC's _requestParamUpdates dereferences a null pointer for an unknown name (code reading); MAVSDK logs it.",
         "§C22, §3.3"),
    Rule("CDF203", "range-target-unknown", E, E, E,
         "parameterrange@parameter names an existing parameter other than its own.",
         "MAVSDK skips the parameter ('Unknown roption type'); QGC's _updateRanges risks a null dereference.",
         "§C23, §4.3, §3.3"),
    Rule("CDF204", "roption-not-in-target", W, W, W,
         "The target of a parameterrange has options and every roption value is one of them.",
         "MAVSDK intersects roptions with the target's options, QGC replaces the list: they disagree.",
         "§C23, §4.4"),
    Rule("CDF205", "condition-syntax", W, I, W,
         "condition is NAME(=|!=|>|<)VALUE tokens joined by single-space AND/OR, names exist, no > or <.",
         "QGC splits on single spaces and compares > and < as strings; MAVSDK ignores conditions.",
         "§C24, §3.4"),
    Rule("CDF206", "trigger-not-canonical", W, I, W,
         "Option values that trigger exclusions, ranges or conditions are canonical decimal integers.",
         "QGC compares option text with rawValueString(): 01 or 1.0 never match; floats match only by accident.",
         "§C25, §3.4"),
    Rule("CDF207", "decimalplaces", W, I, W,
         "decimalPlaces is spelled camelCase (decimalplaces is silently ignored by QGC).",
         "QDom attribute lookup is case-sensitive.",
         "§C26, §3.1"),
    Rule("CDF208", "cam-mode", I, I, I,
         "If CAM_MODE is present: control=\"0\" and options 0 (photo) and 1 (video).",
         "QGC then switches modes with PARAM_EXT_SET instead of MAV_CMD_SET_CAMERA_MODE; the camera must serve it.",
         "§C27, §1.2"),
    Rule("CDF209", "reserved-name", I, I, I,
         "Reserved CAM_* names (camera_def.md §Common Parameters) are numeric settings, not bool/custom/string.",
         "GCSs give reserved names special UI; a different meaning confuses them.",
         "§C28, §1.2"),
    Rule("CDF210", "localization", W, I, W,
         "locale names are ll_CC; each original is some description or option name and no structural text; "
         "no entities or markup characters in original/translated; one <localization>.",
         "QGC translates by raw byte replacement on the whole file.",
         "§C29, §3.4"),
    Rule("CDF211", "unknown-name", I, I, I,
         "Elements and attributes outside the CDF vocabulary (e.g. <videostreams>, v4l_id, options@default).",
         "All parsers ignore them: harmless, but often a typo (decimalplaces) or a misunderstanding.",
         "§C34"),
    Rule("CDF212", "parameter-count", E, E, E,
         "At most 65535 parameters (PARAM_EXT_VALUE.param_count is uint16).",
         "The count cannot be represented on the wire. (Unreachable while CDF006 caps a file at 5000 elements; "
         "kept for callers that raise the cap.)",
         "§C30"),
    Rule("CDF213", "readonly-control", W, W, W,
         "A readonly=\"1\" parameter with options is not control=\"1\" (an editable control that never sends).",
         "QGC never sends readonly facts; the user sees a control that does nothing.",
         "§C35"),
    Rule("CDF214", "identity-text", W, W, W,
         "<model> and <vendor> fit CAMERA_INFORMATION (at most 31 UTF-8 bytes) and contain no path separators.",
         "QGC and MAVSDK build cache file names from them.",
         "§C4"),
    # --- against what the camera reports (validate(..., camera_info=...)) ---------------------------------
    Rule("CDF300", "version-mismatch", W, W, W,
         "definition@version equals CAMERA_INFORMATION.cam_definition_version and is > 0.",
         "Both GCSs cache by vendor+model+version from CAMERA_INFORMATION: a stale or 0 version is never refreshed.",
         "§C3, §3.5, §4.5"),
    Rule("CDF301", "identity-mismatch", W, W, W,
         "<model>/<vendor> equal CAMERA_INFORMATION model_name/vendor_name.",
         "GCSs take the cache key from CAMERA_INFORMATION and the UI from the file.",
         "§C4"),
    Rule("CDF302", "uri", W, W, W,
         "cam_definition_uri: at most 139 characters, scheme http(s):// or mftp://, no comp= part, "
         "no .xml.xz over HTTP.",
         "char[140] on the wire; QGC knows only mftp; neither GCS inflates xz fetched over HTTP (measured for MAVSDK).",
         "§C31, §1.4, §D"),
    Rule("CDF303", "wire-type-mismatch", E, E, E,
         "Each parameter's type equals the PARAM_EXT type the camera answers with.",
         "MAVSDK requests typed values and fails on a mismatch ('Comparison type mismatch').",
         "§C30, §4.5"),
    Rule("CDF304", "not-answered", W, W, W,
         "Every non-writeonly parameter is answered by the camera (PARAM_EXT_REQUEST_LIST/READ).",
         "QGC retries and times out; MAVSDK shows no value.",
         "§C35"),
)

RULES_BY_ID: dict[str, Rule] = {r.id: r for r in RULES}


class Disagreement(NamedTuple):
    """A class of mutants where the mavsdk profile's verdict is not what real MAVSDK did, and why.
    bench/cdf_mutants.py skips a disagreement this row matches: one of `where` ("measure/direction", its
    terms), one of `kinds` among the mutant's mutation kinds, the mavsdk profile's error rules (sorted) one of
    `errors`, and the `messages` pattern found in every error message."""

    key: str
    where: tuple[str, ...]
    kinds: tuple[str, ...]
    errors: tuple[tuple[str, ...], ...]
    messages: str  # a regular expression
    faults: str
    mavsdk_does: str
    profile_says: str
    why: str
    example: str  # one mutant of the class as the bench prints it: seed file, then its faults


_INT = r"(u?int(8|16|32|64)|bool)"
_FLOAT = r"(float|double)"

# Every class bench/cdf_mutants.py still reports after the fixes it led to (the fixes are in the rule rows).
DISAGREEMENTS: tuple[Disagreement, ...] = (
    Disagreement("stoi-lenient", ("mavsdk/profile-errors",), ("bad-value", "retype"), (("CDF120",),),
                 rf"valid {_INT}\b|plain decimal integer|outside the {_INT} range|\({_INT}\)",
                 "an integer or bool value MAVSDK's std::stoi/stoll read leniently (CDF120): a prefix of `1e3`, "
                 "`1.5`, `0x10`, `35.0` (also a float parameter retyped to an integer type), or a number outside "
                 "the type (`99999` as uint8, `-10` as uint64, `2` as bool)",
                 "loads the parameter with the prefix (1e3 -> 1, 0x10 -> 0) or the number cast into the type "
                 "(99999 -> 159 as uint8, 2 -> true) and drops nothing",
                 "error",
                 "kept on purpose: the value MAVSDK shows and sends is not the file's (another option, another "
                 "range), QGC ignores the value with a warning and MAVProxy rejects the file; the same rule "
                 "catches `abc`, which crashes MAVSDK",
                 "e90_camera_exclusions_beside_options.xml bad-value:parameter@min='0x10'"),
    Disagreement("stof-lenient", ("mavsdk/profile-errors",), ("bad-value", "retype"), (("CDF120",),),
                 rf"valid {_FLOAT}\b|finite decimal number|does not fit a|\({_FLOAT}\)",
                 "a float value only C's strtof reads (CDF120): hexadecimal `0x10`, `nan`",
                 "loads it (std::stof reads 0x10 as 16 and nan as NaN) and drops nothing",
                 "error",
                 "kept on purpose: QGC's toFloat() and MAVProxy's float() refuse hexadecimal (QGC ignores the "
                 "value, MAVProxy rejects the file), and a NaN default or range never compares, so the "
                 "control cannot be set back",
                 "generated:wiris-enterprise misplace-exclusions:beside-option + bad-value:parameter@max='0x10'"),
    Disagreement("nameless-skipped", ("mavsdk/profile-errors",), ("name",),
                 (("CDF112",), ("CDF113",), ("CDF119",), ("CDF123",), ("CDF127",), ("CDF203",)), "",
                 "a parameter MAVSDK skips (custom or string type, no default, no range, ...) whose name is "
                 "also emptied",
                 "skips it like any other, but the harness sees a dropped parameter as a file name MAVSDK "
                 "does not answer, and an empty name cannot be asked for: it reports 'loads every parameter'",
                 "error (the skip rule)",
                 "the profile is right: MAVSDK skips by type, default, range and options, whatever the name "
                 "(reference §4.3); the gap is the harness's, which measures drops by name",
                 "gazebo_camera.xml name:empty + retype:type=custom"),
    Disagreement("duplicate-broken-copy", ("mavsdk/profile-errors", "drops/dropped-set"), ("duplicate",),
                 (("CDF123",),), "",
                 "a duplicated parameter whose one copy is broken (CDF117 with CDF123 on one copy)",
                 "keeps the good copy and drops nothing",
                 "error (the broken copy's drop rule)",
                 "which copy MAVSDK keeps is not specified; the file is ambiguous, fix both findings",
                 "generated:wiris-pro duplicate:parameter + drop-attr:option@value"),
)


def rule(rule_id: str) -> Rule:
    return RULES_BY_ID[rule_id]


def _cell(text: str) -> str:
    """A Markdown table cell: element names in backticks, or Markdown renders them as (invisible) HTML tags."""
    if text.startswith("`"):
        return text.replace("|", "\\|")
    return re.sub(r"(<[^<>|]+>)", r"`\1`", text).replace("|", "\\|")


def render_markdown() -> str:
    """cdf/schema/RULES.md, generated from RULES."""
    out = [
        "# CDF validation rules",
        "",
        "Generated from `cdf/validation/rules.py` by `python -m cdf.validation.rules > cdf/schema/RULES.md`;",
        "a test fails when this file and the table differ. Rule ids are stable and never reused.",
        "",
        "Profiles (`wiris cdf validate --profile`): **qgc** = what QGroundControl's parser needs; **mavsdk** =",
        "what MAVSDK 4.1.0 needs without dropping anything (a file it rejects or a parameter it silently",
        "skips is an error; what it loads but silently loses, such as a misplaced exclusion, a warning);",
        "**strict** (default) = both, plus what MAVProxy's parser rejects and the interoperability warnings.",
        "A file is valid in a profile when it has no finding of severity `error` there; `-` = not reported.",
        "Sources: `ref` points at ../shared/reference/camera-definition-files.md (§C = its rule list,",
        "§3 QGC, §4 MAVSDK, §D facts measured with the real parsers). CDF3xx rules need a",
        "`CameraInfo` (what the camera reports) and are skipped without one.",
        "",
        "| id | name | qgc | mavsdk | strict | checks | why | ref |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in RULES:
        cells = [r.id + (" (retired)" if r.retired else ""), r.name, r.qgc or "-", r.mavsdk or "-",
                 r.strict or "-", r.checks, r.why, r.ref]
        out.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    out += ["", "## Where the mavsdk profile and real MAVSDK still disagree", "",
            "Measured by `bench/cdf_mutants.py` (seeded single- and double-fault mutants of the corpus, the",
            "wild files of tests/data/cdf and the generated definitions, through MAVSDK 4.1.0 and MAVProxy).",
            "`bench/cdf_mutants.py` skips the disagreements a row explains (it prints them by class) and fails on",
            "any other.", "",
            "| class | faults | MAVSDK does | mavsdk profile | why | example mutant |", "|---|---|---|---|---|---|"]
    for d in DISAGREEMENTS:
        cells = [d.key, d.faults, d.mavsdk_does, d.profile_says, d.why, f"`{d.example}`"]
        out.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    print(render_markdown(), end="")
