"""Ctrl-C that reaches the program as a :class:`KeyboardInterrupt`, wherever it lands.

Python raises :class:`KeyboardInterrupt` in whatever Python code runs when SIGINT arrives.  Inside
CasADi that code is often called by CasADi's C++ core (``DM.full`` calls the Python ``toarray``,
which reads the Python property ``shape``), and the core does not pass the exception on: it
returns a result with the exception still set (Python then raises ``SystemError: ... returned a
result with an exception set``, caused by the interrupt), or converts it into an error that the
caller takes for a failed evaluation, and the run goes on as if Ctrl-C had not been pressed.

:func:`interrupts_outside_casadi` installs a SIGINT handler that raises the interrupt only in
code outside CasADi's package; landing inside it, the handler sends SIGINT again a moment later
(every 20 ms until the program is back in its own code, which, with gaitopt's solves of at most
seconds each, is soon).  :func:`caused_by_interrupt` recognises an exception that an interrupt
turned into another one, for the cases that still slip through.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType

__all__ = ["interrupts_outside_casadi", "caused_by_interrupt", "RETRY_SECONDS"]

#: Delay before an interrupt that landed inside CasADi is delivered again.
RETRY_SECONDS = 0.02


def _inside_casadi(frame: FrameType | None) -> bool:
    """Whether ``frame`` (the Python code that was running) belongs to the ``casadi`` package."""
    casadi = sys.modules.get("casadi")
    where = getattr(casadi, "__file__", None)
    if frame is None or not where:
        return False
    return frame.f_code.co_filename.startswith(os.path.dirname(where) + os.sep)


@contextlib.contextmanager
def interrupts_outside_casadi() -> Iterator[None]:
    """While the block runs, Ctrl-C raises :class:`KeyboardInterrupt` only outside CasADi's code.

    The previous SIGINT handler is restored afterwards.  Nothing changes where Ctrl-C does not
    raise :class:`KeyboardInterrupt` already (a handler of the caller's own, ``SIG_IGN`` in a
    background job) or outside the main thread (where Python cannot set handlers).

    Yields
    ------
    None
    """
    main = threading.main_thread()
    if (
        threading.current_thread() is not main
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield
        return
    retry: list[threading.Timer] = []
    # The block's end and a retry's signal exclude each other: a retry timer already running when
    # the block ends would otherwise signal after the handler is restored, and that late Ctrl-C
    # would strike whatever the program does next (its exit, with status -2 instead of 130).
    lock, ended = threading.Lock(), [False]

    def again() -> None:
        with lock:
            retry.clear()
            if ended[0]:
                return
            with contextlib.suppress(OSError, ValueError):  # the main thread has ended
                signal.pthread_kill(main.ident, signal.SIGINT)

    def handler(signum: int, frame: FrameType | None) -> None:
        if not _inside_casadi(frame):
            raise KeyboardInterrupt
        if not retry:  # not now: CasADi's C++ core would lose it
            timer = threading.Timer(RETRY_SECONDS, again)
            timer.daemon = True
            retry.append(timer)
            timer.start()

    signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        with lock:
            ended[0] = True
            pending = bool(retry)
            for timer in list(retry):
                timer.cancel()
        try:
            # signal.signal first runs the handler of a signal already received (a retry sent
            # just before the block ended): its KeyboardInterrupt, then the handler restored
            signal.signal(signal.SIGINT, signal.default_int_handler)
        except KeyboardInterrupt:
            signal.signal(signal.SIGINT, signal.default_int_handler)
            raise
        if pending:  # pressed while the block's last CasADi call ran: it still counts
            raise KeyboardInterrupt


def caused_by_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is a :class:`KeyboardInterrupt` or was raised because of one (its chain of
    ``__cause__`` and ``__context__`` holds one: CasADi's ``SystemError``)."""
    seen: set[int] = set()
    chain: list[BaseException | None] = [exc]
    while chain:
        link = chain.pop()
        if link is None or id(link) in seen:
            continue
        if isinstance(link, KeyboardInterrupt):
            return True
        seen.add(id(link))
        chain += [link.__cause__, link.__context__]
    return False
