"""A plain-text progress bar on stderr, and durations as ``1h02m03s``."""

from __future__ import annotations

import sys
import time


class Progress:
    """Plain-text progress bar on stderr (one line per update when not a terminal)."""

    def __init__(self, total: int, label: str, width: int = 30) -> None:
        self.total, self.label, self.width = total, label, width
        self.done = 0
        self.t0 = time.monotonic()
        self.tty = sys.stderr.isatty()

    def update(self, note: str = "") -> None:
        self.done += 1
        el = time.monotonic() - self.t0
        eta = el / self.done * (self.total - self.done)
        fill = int(self.width * self.done / max(self.total, 1))
        line = (f"[{self.label}] [{'#' * fill}{'.' * (self.width - fill)}] "
                f"{self.done}/{self.total} {hms(el)} elapsed, eta {hms(eta)} {note}")
        if self.tty:
            sys.stderr.write("\r" + line[:160].ljust(160))
            if self.done == self.total:
                sys.stderr.write("\n")
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()


def hms(s: float) -> str:
    """``s`` seconds as ``2m03s``, or ``1h02m03s`` from an hour on."""
    s = int(round(s))
    return f"{s // 3600}h{s % 3600 // 60:02d}m{s % 60:02d}s" if s >= 3600 else \
        f"{s // 60}m{s % 60:02d}s"
