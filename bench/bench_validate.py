"""Validate the whole CDF corpus vs a bare lxml parse of the same files, side by side in one run.

    .venv/bin/python bench/bench_validate.py [--repeat 7]

Both sides get the same in-memory bytes (xz inflated up front for the bare parse, as validate does it
itself). Prints medians, the ratio, validate without the XSD pass and with xmlschema forced on every file
(no fast path: the conservative pre-check in cdf/validation/schema.py normally skips xmlschema for files
that conform), and peak memory (tracemalloc for one validation pass; ru_maxrss of the process). Target:
ratio <= 8 for validate / bare parse; also printed: the median and range of the per-iteration ratios, and the ratio
of the two sides' fastest iterations.
"""

from __future__ import annotations

import argparse
import lzma
import resource
import statistics
import sys
import time
import tracemalloc
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from lxml import etree  # noqa: E402

from cdf.validate import validate_bytes  # noqa: E402
from cdf.validation import engine, schema  # noqa: E402

CORPUS = REPO.parent / "shared" / "corpus" / "cdf"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    files = sorted(CORPUS.rglob("*.xml")) + sorted(CORPUS.rglob("*.xml.xz"))
    raw = [f.read_bytes() for f in files]
    plain = [lzma.decompress(d) if d.startswith(b"\xfd7zXZ\x00") else d for d in raw]
    schema.compiled_schema()  # one-off compile (~0.3 s), not per file

    def bare() -> None:
        for d in plain:
            etree.fromstring(d)

    def full() -> None:
        for d, f in zip(raw, files):
            validate_bytes(d, f.name, "strict")

    def without_xsd() -> None:
        real = engine.schema_hits
        engine.schema_hits = lambda root: []  # the same pipeline minus the XSD pass
        try:
            full()
        finally:
            engine.schema_hits = real

    def xmlschema_always() -> None:
        real = engine.schema_hits
        engine.schema_hits = schema.xmlschema_hits  # no fast path
        try:
            full()
        finally:
            engine.schema_hits = real

    def timed(*fns) -> list[list[float]]:
        # interleaved per iteration: a burst of load on the shared machine hits every side alike
        samples: list[list[float]] = [[] for _ in fns]
        for _ in range(args.repeat):
            for i, fn in enumerate(fns):
                t = time.perf_counter()
                fn()
                samples[i].append(time.perf_counter() - t)
        return samples

    def medians(*fns) -> list[float]:
        return [statistics.median(x) for x in timed(*fns)]

    from cdf.xmlsafe import parse_xml

    need_xmlschema = sum(not schema.conforms_fast(parse_xml(d, "x")[0]) for d in plain)
    bs, vs, ns = timed(bare, full, without_xsd)
    b, v, n = (statistics.median(x) for x in (bs, vs, ns))
    # each iteration's own ratio (its sides ran back to back), then the median and spread of those
    per_run = sorted(x / y for x, y in zip(vs, bs))
    a = medians(xmlschema_always)[0]
    tracemalloc.start()
    full()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    total_kb = sum(len(d) for d in plain) / 1024
    print(f"corpus: {len(files)} files, {total_kb:.0f} KiB of XML; median of {args.repeat} interleaved runs")
    print(f"{'bare lxml parse':<34}{b * 1000:9.2f} ms")
    print(f"{'validate (strict, all rules)':<34}{v * 1000:9.2f} ms")
    print(f"{'validate without the XSD pass':<34}{n * 1000:9.2f} ms")
    print(f"{'validate, xmlschema on every file':<34}{a * 1000:9.2f} ms  ({a / b:.0f}x; the fast path sent "
          f"{need_xmlschema} of {len(files)} files to xmlschema)")
    print(f"ratio validate / bare parse: {v / b:.1f}x (target <= 8x: {'met' if v / b <= 8 else 'NOT met'}); "
          f"without the XSD pass: {n / b:.1f}x")
    print(f"per-iteration ratios: median {statistics.median(per_run):.1f}x, "
          f"range {per_run[0]:.1f}x-{per_run[-1]:.1f}x over {len(per_run)} iterations; "
          f"best of each side (timeit's way of leaving the machine's load out): {min(vs) / min(bs):.2f}x")
    print("(the machine is shared: compare ratios from one run, not absolute times across runs)")
    print(f"peak memory: tracemalloc {peak / 1e6:.1f} MB for one validation pass; "
          f"ru_maxrss {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB (whole process)")


if __name__ == "__main__":
    main()
