"""A fake trigger microcontroller on a pseudo-terminal, for tests and examples without hardware.

It speaks the line protocol of :mod:`tensor_cosdi.io.triggers` and can be
told to answer late, never, or with garbage, and to disconnect.
"""

from __future__ import annotations

import os
import threading
import time

__all__ = ["FakeTriggerDevice"]


class FakeTriggerDevice:
    """A simulated trigger microcontroller on a pseudo-terminal, for tests and dry runs (POSIX
    only).

    ``port`` is the device path to open with :class:`SerialDevice`.  The
    behaviour is scripted per command line (exact text, e.g. ``"TRIG 2"``,
    or a verb such as ``"PROJ"``):

    * ``delays`` — seconds to wait before answering;
    * ``late_once`` — answer only after this many seconds the *first* time
      (a retry then succeeds);
    * ``silent`` — never answer;
    * ``garbage_once`` — answer garbage the first time;
    * ``refuse`` — answer ``ERR`` (the device's own refusal);
    * ``echo`` — echo every line first.

    ``fired`` lists the frames actually triggered (a repeated ``TRIG n`` is
    acknowledged without firing again); ``on_trigger(n)``, if given, is
    called when frame ``n`` fires (e.g. to write a simulated camera frame);
    ``disconnect()`` pulls the plug.
    """

    def __init__(
        self,
        *,
        delays=None,
        late_once=None,
        silent=(),
        garbage_once=(),
        refuse=(),
        echo: bool = False,
        on_trigger=None,
    ):
        if os.name != "posix":
            raise OSError("FakeTriggerDevice needs POSIX pseudo-terminals (Linux, macOS)")
        import tty

        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.port = os.ttyname(self.slave)
        self.delays = dict(delays or {})
        self.late_once = dict(late_once or {})
        self.silent = set(silent)
        self.garbage_once = set(garbage_once)
        self.refuse = set(refuse)
        self.echo = echo
        self.on_trigger = on_trigger
        self.fired: list[int] = []
        self.received: list[str] = []
        self._seen: set[str] = set()
        self._stop = threading.Event()
        # the descriptors are used and closed only under this lock, and closed once: a closed
        # number may be reused by the process for another file at any moment
        self._fd_lock = threading.Lock()
        self._closed = False
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _match(self, mapping, line):
        verb = line.split()[0]
        if isinstance(mapping, dict):
            return mapping.get(line, mapping.get(verb))
        return line in mapping or verb in mapping

    def _serve(self):
        import select

        buf = b""
        while not self._stop.is_set():
            with self._fd_lock:
                if self._closed:
                    return
                try:
                    ready, _, _ = select.select([self.master], [], [], 0.05)
                    chunk = os.read(self.master, 1024) if ready else None
                except OSError:
                    return
            if chunk is None:
                continue
            if not chunk:
                return
            buf += chunk
            while b"\n" in buf:
                raw, buf = buf.split(b"\n", 1)
                line = raw.decode("ascii", errors="replace").strip()
                if line:
                    self._answer(line)

    def send(self, text):
        """Write one reply line to the host, as the device would (nothing once closed)."""
        with self._fd_lock:
            if self._closed:
                return
            try:
                os.write(self.master, (text + "\n").encode("ascii"))
            except OSError:
                pass

    def _answer(self, line):
        self.received.append(line)
        first = line not in self._seen
        self._seen.add(line)
        if self.echo:
            self.send(line)
        if self._match(self.silent, line):
            return
        delay = self._match(self.delays, line) or 0.0
        if first and self._match(self.late_once, line) is not None:
            delay = max(delay, self._match(self.late_once, line))
        if delay:
            time.sleep(delay)
        if first and self._match(self.garbage_once, line):
            self.send("#$%?!")
            return
        verb, *args = line.split()
        if self._match(self.refuse, line):
            self.send(f"ERR {verb} refused")
            return
        if verb == "TRIG":
            n = int(args[0]) if args and args[0].isdigit() else None
            if n is None:
                self.send("ERR TRIG needs a frame number")
                return
            if not self.fired or self.fired[-1] != n:
                self.fired.append(n)
                if self.on_trigger is not None:
                    self.on_trigger(n)
            self.send(f"OK TRIG {n}")
        elif verb in ("PING", "DMD", "DM", "PROJ"):
            self.send(f"OK {verb}")
        else:
            self.send(f"ERR {verb} unknown command")

    def disconnect(self):
        """Close the device end: the host's next read or write fails.  Idempotent; each
        descriptor is closed exactly once and never used afterwards."""
        self._stop.set()
        with self._fd_lock:
            if self._closed:
                return
            self._closed = True
            for fd in (self.master, self.slave):
                try:
                    os.close(fd)
                except OSError:
                    pass
        if self._thread is not threading.current_thread():
            self._thread.join(timeout=1.0)

    close = disconnect
