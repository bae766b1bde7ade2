"""How far a run over many files got, always visible on stderr.

``mode``: ``"bar"`` (a tqdm bar: on a terminal), ``"lines"`` (stderr is a file or a pipe:
a line when the run starts, one every ``interval`` seconds, and one at the end, each with
the files done out of the total, how many came from the cache, the rate and the estimated
time left) or ``"none"``.
"""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

MODES = ("bar", "lines", "none")
#: Seconds between two progress lines (``"lines"``).
INTERVAL_S = 5.0


def mode_for(stream: Any = None, enabled: bool = True) -> str:
    """``"bar"`` on a terminal, ``"lines"`` otherwise, ``"none"`` when not ``enabled``.

    >>> import io
    >>> mode_for(io.StringIO()), mode_for(io.StringIO(), enabled=False)
    ('lines', 'none')
    """
    if not enabled:
        return "none"
    stream = sys.stderr if stream is None else stream
    try:
        return "bar" if stream.isatty() else "lines"
    except (AttributeError, ValueError):
        return "lines"


def _duration(seconds: float) -> str:
    """``75`` -> ``"1 min 15 s"``.

    >>> _duration(75), _duration(4.2), _duration(3700)
    ('1 min 15 s', '4 s', '1 h 01 min')
    """
    s = int(round(seconds))
    if s >= 3600:
        return f"{s // 3600} h {s % 3600 // 60:02d} min"
    if s >= 60:
        return f"{s // 60} min {s % 60} s"
    return f"{s} s"


class Progress:
    """Progress of ``total`` files, labelled ``label``.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> p = Progress(4, "lines", "materials", interval=0, stream=out, clock=iter([0.0, 1.0, 2.0]).__next__)
    >>> p.update(2, cached=1)
    >>> p.close()
    >>> print(out.getvalue(), end="")
    materials: 0/4 files
    materials: 2/4 files (1 from the cache), 2.0 files/s, about 1 s left
    materials: 2/4 files in 2 s (1 from the cache)
    """

    def __init__(
        self,
        total: int,
        mode: str = "lines",
        label: str = "files",
        *,
        interval: float = INTERVAL_S,
        stream: TextIO | None = None,
        clock: Any = time.monotonic,
        position: int = 0,
    ) -> None:
        if mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
        self.total, self.mode, self.label = int(total), mode, label
        self.interval, self.clock = float(interval), clock
        self.stream = sys.stderr if stream is None else stream
        self.done = self.cached = 0
        self.shown = (0, 0)
        self.t0 = clock()
        self.last = self.t0
        self.bar = None
        if mode == "bar":
            from tqdm.auto import tqdm

            self.bar = tqdm(
                total=self.total,
                unit="file",
                desc=label,
                file=self.stream,
                leave=False,
                position=position,
                dynamic_ncols=True,
            )
        elif mode == "lines":
            self._line(f"{self.label}: 0/{self.total} files")

    def _line(self, text: str) -> None:
        try:
            print(text, file=self.stream, flush=True)
        except (OSError, ValueError):  # a closed stderr is not worth the run
            pass

    def update(self, done: int, cached: int = 0) -> None:
        """``done`` files finished so far, ``cached`` of them from the cache."""
        step = done - self.done
        self.done, self.cached = done, cached
        if self.bar is not None:
            if cached:
                self.bar.set_postfix_str(f"{cached} cached", refresh=False)
            self.bar.update(step)
            return
        if self.mode != "lines":
            return
        now = self.clock()
        due = now - self.last >= self.interval or (done == self.total and step > 0)
        if not due or self.shown == (done, cached):
            return
        self.last, self.shown = now, (done, cached)
        self._line(self.status(now))

    def status(self, now: float | None = None) -> str:
        """The progress line: files done, from the cache, rate, time left."""
        now = self.clock() if now is None else now
        elapsed = max(now - self.t0, 1e-9)
        rate = self.done / elapsed
        text = f"{self.label}: {self.done}/{self.total} files"
        if self.cached:
            text += f" ({self.cached} from the cache)"
        text += f", {rate:.1f} files/s"
        if 0 < self.done < self.total and rate > 0:
            text += f", about {_duration((self.total - self.done) / rate)} left"
        elif self.done == 0:
            text += ", starting"
        return text

    def close(self) -> None:
        """End the bar, or print the last line."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None
            return
        if self.mode == "lines":
            elapsed = self.clock() - self.t0
            extra = f" ({self.cached} from the cache)" if self.cached else ""
            self._line(f"{self.label}: {self.done}/{self.total} files in {_duration(elapsed)}{extra}")
            self.mode = "none"

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["INTERVAL_S", "MODES", "Progress", "mode_for"]
