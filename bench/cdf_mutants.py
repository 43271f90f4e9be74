"""Differential test of the CDF validator: single- and double-fault mutants of real and generated camera
definitions through real MAVSDK 4.1.0 (camera plugin over HTTP) and MAVProxy's CameraDefinition, against
`wiris cdf validate` in each profile.

    .venv/bin/python bench/cdf_mutants.py [--count N] [--double 0.5] [--seed 1] [--workers 3] [--show 3]
                                          [--peers-cache FILE [--cached-only]]

--peers-cache keeps what MAVSDK made of each mutant (keyed by the mutant's SHA-256) in a JSON file, written
as it goes, so the validator can be judged again after a fix without running MAVSDK again (same seed = same
mutants); --cached-only judges just the mutants the file has (e.g. while a long run is still measuring).
Delete the file after a change to the harness or to MAVSDK: its results are the old harness's.

Seeds: the corpus files MAVSDK loads (../shared/corpus/cdf), the wild files of tests/data/cdf and the
generated WIRIS/RedEdge definitions. Each mutant applies one fault (or two, with probability --double)
chosen by a seeded generator, so a run is reproducible. Agreement, measured on the mutants where the
harness got an answer from MAVSDK (loads / drops / rejects / crash; timeouts are counted apart):
  mavsdk profile  = "has an error" equals "MAVSDK rejects, crashes or drops a parameter";
  dropped set     = the parameters the mavsdk profile says MAVSDK skips equal the ones it skipped;
  strict          = has an error whenever MAVSDK or MAVProxy rejects/drops (strict is a superset).
QGroundControl is not run (no headless QGC peer), so the qgc profile is not measured here.
It prints the agreement per profile and per mutation class, the disagreements that a row of RULES.md's
disagreement table (cdf/validation/rules.py DISAGREEMENTS) explains, skipped by class with an example, and
every other disagreement class with examples; it exits 1 when there is any of those.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import random
import sys
import tempfile
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "tests")]

import peers  # noqa: E402

CORPUS = REPO.parent / "shared" / "corpus" / "cdf"
WILD = REPO / "tests" / "data" / "cdf"
# corpus files MAVSDK rejects as they are (CDF125): their mutants would say nothing about the fault
REJECTED_SEEDS = {"camera_definition_example.xml", "camera-def-rs-rgb.xml", "storm32_camdef_goprohero5_v244.xml",
                  "storm32_camdef_goprohero5_v248.xml", "storm32_camdef_goprohero7_v248.xml",
                  "storm32mavcamera_goprohero5.xml"}


@dataclass(frozen=True)
class Mutant:
    seed: str
    faults: tuple[str, ...]  # "kind:detail" of each fault applied
    data: bytes


def seeds() -> dict[str, bytes]:
    from cdf.generate import definition_xmls

    out = {p.name: p.read_bytes() for p in sorted(CORPUS.rglob("*.xml")) if p.name not in REJECTED_SEEDS}
    out.update({p.name: p.read_bytes() for p in sorted(WILD.glob("*.xml"))})
    out.update({f"generated:{k}": v for k, v in definition_xmls().items()})
    return out


# ---- faults: each takes (root, rng) and returns a detail string, or None when it does not apply ---------------

BAD_VALUES = ("", "abc", "1.5", "3000000000", "-1", "01", "0x10", " 1", "nan", "1e3", "99999")
TYPES = ("Uint8", "string", "custom", "elapsedSeconds", "uint64", "float", "bool", "int8", "uint16", "double")


def _pick(rng: random.Random, items: list):
    return rng.choice(items) if items else None


def _params(root) -> list:
    return list(root.iter("parameter"))


def f_drop_attr(root, rng):
    el = _pick(rng, [e for e in root.iter() if isinstance(e.tag, str) and e.attrib])
    if el is None:
        return None
    attr = rng.choice(sorted(el.attrib))
    del el.attrib[attr]
    return f"{el.tag}@{attr}"


def f_bad_value(root, rng):
    attr = rng.choice(("default", "min", "max", "step", "value"))
    el = _pick(rng, [e for e in root.iter() if isinstance(e.tag, str) and e.get(attr) is not None])
    if el is None:
        return None
    el.set(attr, rng.choice(BAD_VALUES))
    return f"{el.tag}@{attr}={el.get(attr)!r}"


def f_retype(root, rng):
    p = _pick(rng, _params(root))
    if p is None:
        return None
    p.set("type", rng.choice(TYPES))
    return f"type={p.get('type')}"


DROPPABLE = ("description", "options", "option", "exclusions", "exclude", "model", "vendor", "definition",
             "updates", "parameterranges", "localization")


def f_drop_element(root, rng):
    tag = rng.choice(DROPPABLE)
    el = _pick(rng, list(root.iter(tag)))
    if el is None or el.getparent() is None:
        return None
    el.getparent().remove(el)
    return tag


def f_empty_text(root, rng):
    tag = rng.choice(("model", "vendor", "description", "exclude", "update"))
    el = _pick(rng, list(root.iter(tag)))
    if el is None:
        return None
    el.text = ""
    return tag


def f_duplicate_parameter(root, rng):
    import copy

    p = _pick(rng, _params(root))
    if p is None:
        return None
    p.addnext(copy.deepcopy(p))
    return "parameter"


def f_misplace_exclusions(root, rng):
    ex = _pick(rng, [e for e in root.iter("exclusions") if e.getparent().tag == "option"])
    if ex is None:
        return None
    option = ex.getparent()
    where = rng.choice(("beside-option", "in-parameter", "nested"))
    if where == "beside-option":
        option.addnext(ex)
    elif where == "in-parameter":
        option.getparent().addnext(ex)
    else:
        from lxml import etree

        inner = etree.SubElement(ex, "exclusions")
        for c in [c for c in ex if c.tag == "exclude"]:
            inner.append(c)
    return where


def f_misplace_updates(root, rng):
    up = _pick(rng, [e for e in root.iter("updates") if e.getparent().tag == "parameter"])
    if up is None:
        return None
    desc = up.getparent().find("description")
    if desc is None:
        return None
    desc.append(up)
    return "updates-in-description"


def f_flags(root, rng):
    p = _pick(rng, _params(root))
    if p is None:
        return None
    kind = rng.choice(("ro+wo", "control=false", "control=2", "readonly=1"))
    if kind == "ro+wo":
        p.set("readonly", "1")
        p.set("writeonly", "1")
    elif kind == "readonly=1":
        p.set("readonly", "1")
    else:
        p.set("control", kind.split("=")[1])
    return kind


def f_unknown_target(root, rng):
    el = _pick(rng, list(root.iter("exclude")) + list(root.iter("update")) + list(root.iter("parameterrange")))
    if el is None:
        return None
    if el.tag == "parameterrange":
        el.set("parameter", "NO_SUCH_PARAM")
    else:
        el.text = "NO_SUCH_PARAM"
    return el.tag


def f_rename_tag(root, rng):
    tag = rng.choice(("options", "option", "parameter", "parameters", "description", "exclusions"))
    el = _pick(rng, list(root.iter(tag)))
    if el is None:
        return None
    el.tag = rng.choice((tag.capitalize(), tag + "s", tag[:-1]))
    return f"{tag}->{el.tag}"


def f_name(root, rng):
    p = _pick(rng, _params(root))
    if p is None or p.get("name") is None:
        return None
    kind = rng.choice(("long", "empty", "space", "non-ascii"))
    p.set("name", {"long": "CAM_" + "X" * 16, "empty": "", "space": "CAM X", "non-ascii": "CAM_É"}[kind])
    return kind


TREE_FAULTS: dict[str, Callable] = {
    "drop-attr": f_drop_attr, "bad-value": f_bad_value, "retype": f_retype, "drop-element": f_drop_element,
    "empty-text": f_empty_text, "duplicate": f_duplicate_parameter, "misplace-exclusions": f_misplace_exclusions,
    "misplace-updates": f_misplace_updates, "flags": f_flags, "unknown-target": f_unknown_target,
    "rename-tag": f_rename_tag, "name": f_name,
}


def byte_fault(data: bytes, rng: random.Random) -> tuple[bytes, str]:
    """Faults of the stored bytes: encodings and declarations."""
    text = data.decode("utf-8")
    kind = rng.choice(("utf16", "utf16be-nobom", "utf8-bom", "declare-utf16", "no-declaration", "truncate"))
    body = text.split("?>", 1)[1] if text.startswith("<?xml") else text
    if kind == "utf16":
        return ('<?xml version="1.0" encoding="UTF-16"?>' + body).encode("utf-16"), kind
    if kind == "utf16be-nobom":
        return ('<?xml version="1.0" encoding="UTF-16BE"?>' + body).encode("utf-16-be"), kind
    if kind == "utf8-bom":
        return b"\xef\xbb\xbf" + data, kind
    if kind == "declare-utf16":
        return ('<?xml version="1.0" encoding="UTF-16"?>' + body).encode(), kind
    if kind == "no-declaration":
        return body.lstrip().encode(), kind
    return data[: rng.randrange(len(data) // 2, len(data))], kind


def mutate(name: str, data: bytes, rng: random.Random, n_faults: int) -> Mutant | None:
    from lxml import etree

    root = etree.fromstring(peers.plain_xml(data), etree.XMLParser(remove_blank_text=False,
                                                                   resolve_entities=False, no_network=True))
    faults = []
    byte_kind = None
    for _ in range(n_faults):
        if byte_kind is None and rng.random() < 0.12:
            byte_kind = True
            faults.append("bytes")
            continue
        kind = rng.choice(sorted(TREE_FAULTS))
        detail = TREE_FAULTS[kind](root, rng)
        if detail is None:
            return None
        faults.append(f"{kind}:{detail}")
    out = etree.tostring(root, xml_declaration=True, encoding="UTF-8")
    if byte_kind:
        out, kind = byte_fault(out, rng)
        faults[faults.index("bytes")] = f"bytes:{kind}"
    return Mutant(name, tuple(faults), out)


def make_mutants(count: int, double: float, seed: int) -> list[Mutant]:
    rng = random.Random(seed)
    pool = seeds()
    names = sorted(pool)
    out: dict[bytes, Mutant] = {}  # distinct mutants only: the same bytes would be judged twice
    while len(out) < count:
        name = rng.choice(names)
        m = mutate(name, pool[name], rng, 2 if rng.random() < double else 1)
        if m is not None:
            out.setdefault(m.data, m)
    return list(out.values())


# ---- judging ---------------------------------------------------------------------------------------------------

CACHE_CHUNK = 60  # mutants measured between two writes of the peers cache


def run_mavsdk(mutants: list[Mutant], workers: int, cache_path: Path | None) -> list[peers.MavsdkResult]:
    """MAVSDK's result for each mutant; from the cache when it has the mutant, else measured (and cached)."""
    keys = [hashlib.sha256(m.data).hexdigest() for m in mutants]
    cache = json.loads(cache_path.read_text()) if cache_path is not None and cache_path.exists() else {}
    todo = [k for k in keys if k not in cache]
    data = {k: m.data for k, m in zip(keys, mutants)}
    # in chunks, the cache written after each: a long run that is stopped keeps what it measured
    for start in range(0, len(todo), CACHE_CHUNK):
        chunk = todo[start:start + CACHE_CHUNK]
        with tempfile.TemporaryDirectory(prefix="cdf-mutants-") as tmp:
            fresh = peers.mavsdk_load_definitions([data[k] for k in chunk], Path(tmp), workers=workers)
        for k, r in zip(chunk, fresh):
            cache[k] = _result_json(r)
        if cache_path is not None:
            tmp_path = cache_path.with_name(cache_path.name + ".part")
            tmp_path.write_text(json.dumps(cache))
            tmp_path.replace(cache_path)
        print(f"MAVSDK: {min(start + CACHE_CHUNK, len(todo))}/{len(todo)} mutants measured", file=sys.stderr,
              flush=True)
    # file_parameters from the current harness (it reads the file as MAVSDK does), not from the cache
    return [dataclasses.replace(_result_from_json(cache[k]),
                                file_parameters=peers._file_parameter_names(peers.plain_xml(m.data)))
            for k, m in zip(keys, mutants)]


def _result_json(r: peers.MavsdkResult) -> dict:
    d = dataclasses.asdict(r)
    d["known"] = sorted(r.known)
    d["log"] = "\n".join(x for x in r.log.splitlines() if "ERROR" in x)[:2000]
    return d


def _result_from_json(d: dict) -> peers.MavsdkResult:
    return peers.MavsdkResult(
        accepted=d["accepted"], crashed=d["crashed"], outcome=d["outcome"],
        settings={k: tuple(v) for k, v in d["settings"].items()}, known=frozenset(d["known"]),
        file_parameters=tuple(d["file_parameters"]), requested=tuple(d["requested"]), log=d["log"])


def mavsdk_verdict(m: peers.MavsdkResult) -> str:
    if m.crashed:
        return "crash"
    if m.accepted:
        return "drops" if m.dropped else "loads"
    return "rejects" if m.outcome == "rejected" else m.outcome  # timeout / no-system / harness-error


class Klass(NamedTuple):
    """A disagreement class: which measure, which way, the mutant's fault kinds and the mavsdk profile's
    error rules."""

    measure: str  # mavsdk | drops | strict
    direction: str  # profile-errors | profile-valid | dropped-set
    kinds: tuple[str, ...]
    errors: tuple[str, ...]

    def title(self) -> str:
        return (f"{self.measure}: {DIRECTIONS[self.direction]}; faults {'+'.join(self.kinds)}; "
                f"mavsdk errors {','.join(self.errors) or '-'}")


DIRECTIONS = {"profile-errors": "the profile has an error, MAVSDK loads every parameter",
              "profile-valid": "MAVSDK rejects, crashes or drops (or MAVProxy rejects), the profile has no error",
              "dropped-set": "MAVSDK loaded the file; the parameters it dropped are not the predicted ones"}
MEASURES = {"mavsdk": "mavsdk profile has an error = MAVSDK rejects, crashes or drops a parameter",
            "drops": "mavsdk profile's drop findings = the parameters MAVSDK dropped (MAVSDK loaded the file)",
            "strict": "strict profile has an error where MAVSDK or MAVProxy rejects or drops"}


class Judgement(NamedTuple):
    """One measure on one mutant: agreed (disagreement None), or the class it disagrees in, with a row to print
    and the key of the RULES.md row that explains it (None: unexplained)."""

    measure: str
    kinds: tuple[str, ...]
    disagreement: Klass | None
    row: str
    explained_by: str | None = None


def judge(mut: Mutant, ms: peers.MavsdkResult, verdict: str) -> list[Judgement]:
    from cdf.validate import validate_bytes

    px = peers.mavproxy_load_definition(mut.data)
    reports = {p: validate_bytes(mut.data, "mutant.xml", p) for p in ("mavsdk", "strict")}
    unhappy = verdict != "loads"
    kinds = tuple(sorted({f.split(":")[0] for f in mut.faults}))
    errs = tuple(sorted(reports["mavsdk"].rules("error")))
    messages = tuple(f.message for f in reports["mavsdk"].errors)
    label = f"{mut.seed} {' + '.join(mut.faults)}"
    out = []
    said = not reports["mavsdk"].valid
    klass = None if said == unhappy else Klass("mavsdk", "profile-errors" if said else "profile-valid", kinds, errs)
    out.append(Judgement("mavsdk", kinds, klass,
                         f"{label} | MAVSDK: {_why(ms)} | profile: {_errors(reports['mavsdk'])}"))
    if ms.accepted:
        predicted = {f.parameter for f in reports["mavsdk"].findings
                     if f.rule in peers.MAVSDK_DROP_RULES and f.parameter is not None} & set(ms.file_parameters)
        klass = None if predicted == set(ms.dropped) else Klass("drops", "dropped-set", kinds, errs)
        out.append(Judgement("drops", kinds, klass,
                             f"{label} | dropped {sorted(ms.dropped)} predicted {sorted(predicted)}"))
    if unhappy or not px.accepted:
        who = f"MAVSDK {verdict}" if unhappy else f"MAVProxy rejects ({px.error})"
        klass = None if not reports["strict"].valid else Klass("strict", "profile-valid", kinds, errs)
        out.append(Judgement("strict", kinds, klass, f"{label} | {who}"))
    return [j._replace(explained_by=explanation(j.disagreement, messages)) if j.disagreement else j for j in out]


def explanation(k: Klass, messages: tuple[str, ...]) -> str | None:
    """The key of the RULES.md disagreement row that explains a disagreement of class k whose mavsdk profile
    errors say `messages`, if one does."""
    import re

    from cdf.validation.rules import DISAGREEMENTS

    for d in DISAGREEMENTS:
        if (f"{k.measure}/{k.direction}" in d.where and set(d.kinds) & set(k.kinds) and k.errors in d.errors
                and all(re.search(d.messages, m) for m in messages)):
            return d.key
    return None


def _errors(report) -> str:
    return "; ".join(f"{f.rule} {f.message}" for f in report.errors)[:300] or "no error"


def _counts(rows: list[Judgement]) -> str:
    if not rows:
        return "0 | - | - | - | - | -"
    agree = sum(j.disagreement is None for j in rows)
    explained = sum(j.explained_by is not None for j in rows)
    return (f"{len(rows)} | {agree} | {explained} | {len(rows) - agree - explained} | "
            f"{agree / len(rows):.3f} | {(agree + explained) / len(rows):.3f}")


HEAD = "| judged | agree | explained | unexplained | agree ratio | agree+explained |"


def print_tables(judged: list[Judgement], show: int) -> int:
    """The agreement per profile and per mutation class, the explained classes skipped and the unexplained
    ones with examples; returns the number of unexplained disagreements."""
    print("| profile | measured against " + HEAD)
    print("|---|---|---|---|---|---|---|---|")
    for measure, what in MEASURES.items():
        profile = "strict" if measure == "strict" else "mavsdk"
        print(f"| {profile} | {what} | {_counts([j for j in judged if j.measure == measure])} |")
    print("| qgc | not measured: no headless QGroundControl peer | 0 | - | - | - | - | - |")
    print()
    print("mavsdk profile vs MAVSDK per mutation class (a double-fault mutant counts in each of its kinds):")
    print()
    print("| mutation class " + HEAD)
    print("|---|---|---|---|---|---|---|")
    mavsdk = [j for j in judged if j.measure == "mavsdk"]
    for kind in sorted({k for j in mavsdk for k in j.kinds}):
        print(f"| {kind} | {_counts([j for j in mavsdk if kind in j.kinds])} |")
    print()
    skipped: dict[str, list[str]] = defaultdict(list)
    unexplained: dict[Klass, list[str]] = defaultdict(list)
    for j in judged:
        if j.explained_by is not None:
            skipped[j.explained_by].append(f"{j.measure}: {j.row}")
        elif j.disagreement is not None:
            unexplained[j.disagreement].append(j.row)
    print("explained in cdf/schema/RULES.md (its disagreement table), skipped:" + ("" if skipped else " none"))
    for key, rows in sorted(skipped.items(), key=lambda kv: -len(kv[1])):
        print(f"- {key}: {len(rows)} disagreements, e.g. {rows[0][:300]}")
    print()
    print(f"{len(unexplained)} unexplained disagreement classes" + (":" if unexplained else ""))
    for k, rows in sorted(unexplained.items(), key=lambda kv: -len(kv[1])):
        print(f"- [{len(rows)}] {k.title()}")
        for r in rows[:show]:
            print(f"    {r[:500]}")
    return sum(len(rows) for rows in unexplained.values())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=400)
    ap.add_argument("--double", type=float, default=0.5, help="share of double-fault mutants")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=3)
    ap.add_argument("--show", type=int, default=3, help="examples printed per unexplained class")
    ap.add_argument("--peers-cache", help="JSON file of MAVSDK results to reuse and extend")
    ap.add_argument("--cached-only", action="store_true",
                    help="judge only the mutants the peers cache already has (no MAVSDK run)")
    args = ap.parse_args()
    t0 = time.monotonic()
    mutants = make_mutants(args.count, args.double, args.seed)
    cache_path = Path(args.peers_cache) if args.peers_cache else None
    if args.cached_only:
        if cache_path is None or not cache_path.exists():
            sys.exit("--cached-only needs an existing --peers-cache FILE (hint: run once without --cached-only)")
        have = json.loads(cache_path.read_text())
        mutants = [m for m in mutants if hashlib.sha256(m.data).hexdigest() in have]
    msdk = run_mavsdk(mutants, args.workers, cache_path)
    verdicts = Counter()
    judged: list[Judgement] = []
    for mut, ms in zip(mutants, msdk):
        v = mavsdk_verdict(ms)
        verdicts[v] += 1
        if v in ("loads", "drops", "rejects", "crash"):  # a timeout or a harness failure says nothing
            judged += judge(mut, ms, v)
    print(f"{len(mutants)} distinct mutants ({sum(len(m.faults) == 2 for m in mutants)} double-fault) of "
          f"{len({m.seed for m in mutants})} seeds, seed {args.seed}; MAVSDK: "
          + ", ".join(f"{k} {n}" for k, n in sorted(verdicts.items())))
    print()
    unexplained = print_tables(judged, args.show)
    print(f"\n{time.monotonic() - t0:.0f} s")
    if unexplained:
        print(f"FAIL: {unexplained} disagreements that no row of RULES.md's disagreement table explains",
              file=sys.stderr)
        sys.exit(1)


def _why(ms: peers.MavsdkResult) -> str:
    if ms.accepted:
        return f"dropped {list(ms.dropped)}" if ms.dropped else "loaded"
    lines = [x for x in ms.log.splitlines() if "ERROR" in x or "rror" in x]
    return (lines[0] if lines else ms.outcome)[:200]


if __name__ == "__main__":
    main()
