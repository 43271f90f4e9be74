"""MAVLink 2 signing between the camera client and the emulator (both take --signing-key)."""

from __future__ import annotations

from click.testing import CliRunner

from wiris_tools.cli import cli
from wiris_tools.emulate.runner import start_emulator
from wiris_tools.signing import key_from_text


def test_signed_link_works_and_a_wrong_key_is_refused(tmp_path):
    good = tmp_path / "good.key"
    good.write_text("correct horse battery staple\n")
    bad = tmp_path / "bad.key"
    bad.write_text("a different passphrase\n")
    with start_emulator("wiris-pro", "udpin:127.0.0.1:0", signing_key=key_from_text(good.read_text())) as emu:
        url = f"udpout:127.0.0.1:{emu.link.local_port}"
        ok = CliRunner().invoke(cli, ["camera", "info", "--connect", url, "--signing-key", str(good), "--json"])
        assert ok.exit_code == 0, ok.output
        refused = CliRunner().invoke(cli, ["camera", "info", "--connect", url, "--signing-key", str(bad),
                                           "--wait", "1"])
        assert refused.exit_code == 1 and "no HEARTBEAT" in refused.output
        unsigned = CliRunner().invoke(cli, ["camera", "info", "--connect", url, "--wait", "1", "--timeout", "0.3"])
        assert unsigned.exit_code == 1 and "no answer" in unsigned.output   # unsigned commands are dropped
        assert emu.link.stats["rejected_signature"] > 0
