"""The monitor link both SITL backends keep: every message it receives goes into the tlog and the last
STATUSTEXT lines are kept for tests and messages."""

from __future__ import annotations

import time

from wiris_tools.errors import LinkError
from wiris_tools.link import Link


class MonitorRecord:
    """Mixed into a backend that sets `_link`, `_tlog_file`, `_tlog_lock` and `_statustext`."""

    def _record(self, msg) -> None:
        with self._tlog_lock:
            if not self._tlog_file.closed:
                self._tlog_file.write(int(time.time() * 1e6).to_bytes(8, "big") + msg.get_msgbuf())
        if msg.get_type() == "STATUSTEXT":
            self._statustext.append(msg.text)
            del self._statustext[:-200]

    @property
    def link(self) -> Link:
        if self._link is None:
            raise LinkError("the SITL monitor link is closed", hint="a bug in the test or tool using the harness")
        return self._link

    @property
    def statustext(self) -> list[str]:
        return list(self._statustext)
