"""`wiris --help` must stay fast: no heavy library is imported to print it."""

import json
import subprocess
import sys

HEAVY = ("pymavlink", "lxml", "shapely", "pyproj", "xmlschema", "mavsdk", "jsonschema", "PIL")


def test_help_imports_no_heavy_module():
    code = (
        "import sys, json\n"
        "from click.testing import CliRunner\n"
        "from wiris_tools.cli import cli\n"
        "r = CliRunner().invoke(cli, ['--help'])\n"
        "assert r.exit_code == 0, r.output\n"
        f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


def test_help_lists_groups():
    from click.testing import CliRunner

    from wiris_tools.cli import cli

    result = CliRunner().invoke(cli, ["--help"])
    assert result.exit_code == 0
    assert "cdf" in result.output
