"""Instructions (callgrind) spent validating the corpus vs a bare lxml parse: bench_validate.py's ratio
without the noise of a shared machine, where wall-clock ratios swing by 10 % from run to run.

    .venv/bin/python bench/validate_instructions.py [--against REV]

Needs valgrind. Each measurement is its own process under callgrind, with PYTHONHASHSEED=0 so that counts
repeat: a setup (imports, XSD compile, one warm pass over the corpus), then the same plus three passes of
`bare` (etree.fromstring) or `validate` (validate_bytes, strict, as in bench_validate.py); one pass is the difference over three. With --against, the revision REV (extracted
with `git archive`) is measured the same way, for a before/after of speed work. Instructions are not time:
Python's interpreter runs fewer instructions per cycle than libxml2's parser, so the wall-clock ratio is
higher than the ratio printed here, but a change that saves instructions saves time.
"""

from __future__ import annotations

import argparse
import io
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PASSES = 3


def child(mode: str, repo: str) -> None:
    """What runs under callgrind: setup, then PASSES passes of `mode` (none for "setup")."""
    sys.path.insert(0, repo)
    import lzma

    from lxml import etree

    from cdf.validate import validate_bytes
    from cdf.validation import engine, schema

    corpus = Path(repo).parent / "shared" / "corpus" / "cdf"
    if not corpus.is_dir():
        corpus = REPO.parent / "shared" / "corpus" / "cdf"
    files = sorted(corpus.rglob("*.xml")) + sorted(corpus.rglob("*.xml.xz"))
    raw = [f.read_bytes() for f in files]
    plain = [lzma.decompress(d) if d.startswith(b"\xfd7zXZ\x00") else d for d in raw]
    schema.compiled_schema()
    for d, f in zip(raw, files):
        validate_bytes(d, f.name, "strict")
    for d in plain:
        etree.fromstring(d)
    for _ in range(PASSES if mode != "setup" else 0):
        if mode == "bare":
            for d in plain:
                etree.fromstring(d)
        else:
            if hasattr(engine, "clear_caches"):  # a revision (--against) that memoises values across files
                engine.clear_caches()
            for d, f in zip(raw, files):
                validate_bytes(d, f.name, "strict")


def instructions(mode: str, repo: Path) -> int:
    out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable,
                          __file__, "--child", mode, str(repo)], capture_output=True, text=True,
                         env={**os.environ, "PYTHONHASHSEED": "0"}, check=True)
    m = re.search(r"Collected : (\d+)", out.stderr)
    if m is None:
        raise SystemExit(f"no instruction count from callgrind:\n{out.stderr[-2000:]}")
    return int(m.group(1))


def measure(repo: Path, label: str) -> float:
    with ThreadPoolExecutor(2) as pool:  # one valgrind per core
        setup, bare, validate = pool.map(lambda m: instructions(m, repo), ("setup", "bare", "validate"))
    bare_pass, validate_pass = (bare - setup) / PASSES, (validate - setup) / PASSES
    print(f"{label}: bare parse {bare_pass / 1e6:.1f} M instructions, validate {validate_pass / 1e6:.1f} M, "
          f"ratio {validate_pass / bare_pass:.2f}x")
    return validate_pass


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--against", metavar="REV")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(*args.child)
        return
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not installed (apt install valgrind)")
    with tempfile.TemporaryDirectory() as tmp:
        tree = None
        if args.against:  # extracted first: a bad revision fails before minutes of measuring
            got = subprocess.run(["git", "-C", str(REPO), "archive", args.against], capture_output=True)
            if got.returncode:
                raise SystemExit(f"--against {args.against}: git archive failed: "
                                 f"{got.stderr.decode(errors='replace').strip()} (name a commit, tag or branch)")
            tree = Path(tmp) / "rev"
            tree.mkdir()
            with tarfile.open(fileobj=io.BytesIO(got.stdout)) as tar:
                tar.extractall(tree, filter="data")
        now = measure(REPO, "working tree")
        if tree is not None:
            before = measure(tree, args.against)
            print(f"validate: working tree / {args.against} = {now / before:.3f}")


if __name__ == "__main__":
    main()
