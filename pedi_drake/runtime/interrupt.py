"""Ctrl-C and SIGTERM as a request to stop a run, not as an exception thrown through Drake.

Python's default SIGINT handler raises KeyboardInterrupt wherever the interpreter happens to be,
which inside `Simulator.AdvanceTo` unwinds through C++ and loses everything the run did. Here a
signal only records why the run should stop; the simulator's monitor reads that and ends the
simulation at the current time, so the run is judged and written like any other, marked
`interrupted`. A second signal aborts at once (KeyboardInterrupt), for a user who cannot wait for
the files. The module imports nothing heavy so a program can install it before pydrake loads.
"""

import os
import signal
import threading

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
EXIT_INTERRUPTED = 130  # the shell's code for a program ended by Ctrl-C (128 + SIGINT)


def ctrl_c_raises() -> None:
    """Makes SIGINT (Ctrl-C) raise KeyboardInterrupt in this process, Python's own default, also
    where the process was started with SIGINT ignored: a non-interactive shell ignores it in the
    jobs it starts in the background, their children inherit that, and such a program (a bridge a
    script supervises) would otherwise run on after Ctrl-C until it is killed."""
    signal.signal(signal.SIGINT, signal.default_int_handler)


class StopRequest:
    """Why the run should stop (None: it should not). `install` makes SIGINT and SIGTERM set it."""

    def __init__(self):
        self.reason: str | None = None
        self._previous: dict = {}

    def request(self, reason: str) -> None:
        """Asks the run to stop at the current time; the first reason is kept."""
        if self.reason is None:
            self.reason = reason

    def _handle(self, signum, frame) -> None:
        if self.reason is not None:
            # A second signal while the results are written: the user wants out now.
            self.restore()
            raise KeyboardInterrupt(f"{signal.Signals(signum).name} received twice")
        self.request(f"{signal.Signals(signum).name} received")
        # os.write, not print: a handler may run in the middle of another write to stdout.
        os.write(2, b"\nstopping at the current time; writing what ran (signal again to abort)\n")

    def install(self) -> "StopRequest":
        """Routes SIGINT and SIGTERM here (only the main thread may set signal handlers)."""
        if threading.current_thread() is threading.main_thread() and not self._previous:
            for signum in STOP_SIGNALS:
                self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def restore(self) -> None:
        """Puts back the handlers `install` replaced."""
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous = {}

    def ignore_from_now_on(self) -> None:
        """Ignores SIGINT and SIGTERM for the rest of the process (once its results are written)."""
        if threading.current_thread() is threading.main_thread():
            for signum in STOP_SIGNALS:
                signal.signal(signum, signal.SIG_IGN)
        self._previous = {}

    def __enter__(self) -> "StopRequest":
        return self.install()

    def __exit__(self, *exc) -> None:
        self.restore()
