"""Do two revisions of the validator write the same reports? The guard for speed work on cdf/validation.

    .venv/bin/python bench/validate_same_reports.py [--against HEAD] [--mutations 2400] [--seed 20261123]

Validates the real corpus plus seeded random mutations of it (elements removed, duplicated, moved, renamed,
attributes added, changed or removed, stray text, unknown elements, comments and processing instructions)
in the profiles qgc, mavsdk and strict, once with the working tree and once with the revision `--against`
(extracted with `git archive`), each in its own process, and prints every report that differs.
Exit code 0 when all reports are identical, 1 otherwise. Takes a few minutes: mutants that the fast
path cannot clear go through xmlschema.
"""

from __future__ import annotations

import argparse
import copy
import json
import lzma
import random
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CORPUS = REPO.parent / "shared" / "corpus" / "cdf"
TAGS = ("mavlinkcamera definition model vendor parameters parameter description updates update options option "
        "exclusions exclude parameterranges parameterrange roption localization locale strings foo").split()
ATTRS = ("name value type default min max step control readonly writeonly decimalPlaces decimalplaces unit "
         "parameter condition original translated bogus").split()
VALUES = ["", "x", "-1", "0", "1", "2", "1.5", " 2 ", "99999999999", "1e3", "CAM_EV", "STRING", "uint16", "Uint8",
          "bool", "float", "custom", "string", "CAM_MODE", "A=1 AND B!=2", "X>1", "de_DE", "a&b", "Off"]

# run in a child process with the code root first on sys.path: prints {case:profile: report} as JSON
CHILD = """
import json, sys
sys.path.insert(0, sys.argv[1])
from pathlib import Path
from cdf.validate import validate_bytes
out = {}
for f in sorted(Path(sys.argv[2]).glob("*.xml")):
    data = f.read_bytes()
    for profile in ("qgc", "mavsdk", "strict"):
        r = validate_bytes(data, f.name, profile)
        out[f"{f.name}:{profile}"] = [r.parameters, [[x.rule, x.severity, x.line, x.parameter, x.message]
                                                    for x in r.findings]]
json.dump(out, sys.stdout)
"""


def mutate(data: bytes, rng: random.Random) -> bytes:
    from lxml import etree

    root = etree.fromstring(data)
    elements = [e for e in root.iter() if isinstance(e.tag, str)]
    for _ in range(rng.choice([1, 1, 2, 3])):
        e = rng.choice(elements)
        parent = e.getparent()
        op = rng.randrange(11)
        try:
            if op == 0 and parent is not None:
                parent.remove(e)
            elif op == 1 and parent is not None:
                e.addnext(copy.deepcopy(e))
            elif op == 2 and parent is not None:
                target = rng.choice(elements)
                if target is not e and e not in target.iterancestors():
                    target.append(e)
            elif op == 3:
                e.set(rng.choice(ATTRS), rng.choice(VALUES))
            elif op == 4 and e.attrib:
                e.set(rng.choice(list(e.attrib)), rng.choice(VALUES))
            elif op == 5 and e.attrib:
                del e.attrib[rng.choice(list(e.attrib))]
            elif op == 6:
                e.text = rng.choice(["junk", " ", "", None, "  x  ", "\u00a0"])
            elif op == 7:
                etree.SubElement(e, rng.choice(TAGS)).text = rng.choice([None, "CAM_EV", "x"])
            elif op == 8:
                e.append(etree.ProcessingInstruction("pi", "x") if rng.random() < 0.5 else etree.Comment("c"))
            elif op == 9 and parent is not None:
                e.tag = rng.choice(TAGS)
            elif op == 10 and len(e):
                e[rng.randrange(len(e))].tail = rng.choice(["tail", " ", "\u2003"])
        except (ValueError, TypeError):
            pass  # an operation lxml refuses (e.g. a text on a removed element's slot): skip it
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8")


def reports(code_root: Path, cases: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(code_root), str(cases)], capture_output=True,
                         text=True, check=True, cwd=tempfile.gettempdir())
    return json.loads(out.stdout)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--against", default="HEAD")
    ap.add_argument("--mutations", type=int, default=2400)
    ap.add_argument("--seed", type=int, default=20261123)
    args = ap.parse_args()
    files = sorted(CORPUS.rglob("*.xml")) + sorted(CORPUS.rglob("*.xml.xz"))
    originals = [lzma.decompress(f.read_bytes()) if f.suffix == ".xz" else f.read_bytes() for f in files]
    rng = random.Random(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        cases, old = Path(tmp, "cases"), Path(tmp, "old")
        cases.mkdir()
        old.mkdir()
        for i, data in enumerate(originals):
            (cases / f"corpus-{i:02d}.xml").write_bytes(data)
        for i in range(args.mutations):
            (cases / f"mutant-{i:05d}.xml").write_bytes(mutate(rng.choice(originals), rng))
        archive = subprocess.run(["git", "archive", args.against, "cdf", "templates"], cwd=REPO,
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive, check=True)
        a, b = reports(old, cases), reports(REPO, cases)
    differ = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
    for key in differ[:20]:
        print(f"{key}\n  {args.against}: {a.get(key)}\n  working tree: {b.get(key)}")
    findings = sum(len(v[1]) for v in b.values())
    print(f"{len(b)} reports ({len(files)} corpus files + {args.mutations} mutations, 3 profiles; "
          f"{findings} findings): {len(differ)} differ from {args.against}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
