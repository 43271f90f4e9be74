"""Where the tests find the public corpus: the copies in tests/data/corpus (tests/data/README.md says where
each file comes from and its licence), so that a fresh clone tests without ../shared beside it.

One file of ../shared/corpus/cdf is not copied (its repository states no licence): when ../shared is there
(the team's machines, CI), the CDF corpus includes it; a user's clone tests the copied files.
"""

from __future__ import annotations

from pathlib import Path

DATA = Path(__file__).resolve().parent / "data" / "corpus"
SHARED = Path(__file__).resolve().parents[2] / "shared" / "corpus"

CDF = DATA / "cdf"
PLANS = DATA / "plans"


def _definitions(root: Path) -> list[Path]:
    return sorted(root.rglob("*.xml")) + sorted(root.rglob("*.xml.xz"))


def cdf_files() -> list[Path]:
    """Every corpus definition: the copies, then the ../shared files that have no copy."""
    copied = _definitions(CDF)
    names = {p.relative_to(CDF) for p in copied}
    extra = [p for p in _definitions(SHARED / "cdf") if p.relative_to(SHARED / "cdf") not in names] \
        if (SHARED / "cdf").is_dir() else []
    return copied + extra
