"""Ctrl-C at a chosen point: KeyboardInterrupt raised at the n-th place of a block where CPython 3.11
could deliver it.

A real Ctrl-C (or SIGTERM turned into KeyboardInterrupt) is raised wherever the main thread happens to
be when the interpreter next checks for signals. Stepping n through every such place reaches each one
deterministically, where signals sent at random times find a narrow window once in dozens of runs.

CPython 3.11 checks at a function's entry (RESUME), when a CALL of a C function (a lock's acquire,
say) returns, and at each loop's JUMP_BACKWARD. Other trace events are no such place: an interrupt at
the `line` event of a `with` line that follows its body, say, would report a lock left held that no
real signal can leave. A tracer cannot raise inside the CALL itself, only before the next instruction;
the two are the same unless that instruction lies in another try or `with` than the CALL (the CALL
that ends a `with` body), where the point is skipped.
"""

from __future__ import annotations

import dis
import functools
import gc
import sys
import threading

_CHECKED_AFTER = frozenset({dis.opmap["CALL"], dis.opmap["JUMP_BACKWARD"]})


@functools.lru_cache(maxsize=None)
def _handlers(code) -> tuple:
    return tuple(dis._parse_exception_table(code))  # CPython 3.11's table: (start, end, target, depth, lasti)


def _handler(code, offset: int):
    """The exception table entry that catches an exception raised at `offset`, or None."""
    return next((h for h in _handlers(code) if h.start <= offset < h.end), None)


class InterruptAt:
    """`with InterruptAt(n) as at:` raises KeyboardInterrupt at the n-th signal check of the functions
    called inside the block (this thread only); `at.fired` says whether it got that far."""

    def __init__(self, n: int) -> None:
        self.n, self.count, self.fired = n, 0, False
        self._calls = 0  # Python frames entered so far
        self._last: dict[int, tuple] = {}  # id(frame) -> (its last opcode, its offset, self._calls then)

    def _check(self) -> None:
        if self.count == self.n:
            self.fired = True
            raise KeyboardInterrupt
        self.count += 1

    def _trace(self, frame, event, arg):
        if self.fired:
            return None
        if event == "call":  # RESUME
            if frame.f_code is _EXIT:  # the block is over
                return None
            self._calls += 1
            frame.f_trace_opcodes = True
            self._check()
        elif event == "opcode":
            code, here = frame.f_code, frame.f_lasti
            last, at, calls = self._last.get(id(frame), (None, None, None))
            self._last[id(frame)] = (code.co_code[here], here, self._calls)
            # after a CALL only when no Python frame ran in it: returning from one checks nothing
            if last in _CHECKED_AFTER and calls == self._calls and _handler(code, at) == _handler(code, here):
                self._check()
        elif event == "return":
            self._last.pop(id(frame), None)
        return self._trace

    def __enter__(self) -> "InterruptAt":
        # no garbage collection inside the block: a callback it runs there (a WeakSet's, as a cycle dies)
        # would be interrupted now and then, and Python drops an exception raised in a callback with a
        # warning, so the count of places would vary from run to run
        self._gc_was_enabled = gc.isenabled()
        gc.disable()
        sys.settrace(self._trace)
        return self

    def __exit__(self, *exc: object) -> None:
        sys.settrace(None)
        if self._gc_was_enabled:
            gc.enable()


_EXIT = InterruptAt.__exit__.__code__


def finishes(fn, *args, within_s: float = 10.0) -> bool:
    """Whether fn(*args) returns within `within_s`, run on a helper thread: after an interrupt, a lock left
    held then fails the test instead of hanging it."""
    helper = threading.Thread(target=fn, args=args, daemon=True)
    helper.start()
    helper.join(within_s)
    return not helper.is_alive()
