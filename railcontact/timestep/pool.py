"""Wheelsets stepped in parallel in worker processes.

A :class:`WheelsetPool` owns N :class:`~railcontact.timestep.WheelsetContact` s spread over
worker processes, each wheelset always in the same process (its warm-start memory stays
there). One call of :meth:`WheelsetPool.step` sends every wheelset the keyword arguments
of :meth:`WheelsetContact.solve` and returns their results in wheelset order: one round
trip through a pipe per worker process and step, the workers solving at the same time
(and, with ``here``, this process solving a share of its own meanwhile).

Processes as well as threads: the compiled kernels release the interpreter, so wheelsets
on threads of one process overlap, but only in part, because the Python that runs between
the kernels of a step holds it (two wheelsets on two threads take 0.6-0.75 of one after
the other on two free cores). In two processes they run on two cores at once, at the cost
of a pipe's round trip a step.

The workers are started once with the ``spawn`` method (safe after the compiled kernels,
FFTW and threads are initialised in the host; each worker loads the compiled kernels from
their on-disk cache), build
their wheelsets from picklable descriptions (:class:`WheelsetDescription`) and end when
the pool is closed, when the host process ends (a worker sees its pipe close) or on
garbage collection of the pool.
"""

from __future__ import annotations

import multiprocessing
import multiprocessing.spawn
import os
import pickle
import signal
import subprocess
import sys
import threading
import time
import traceback
import weakref
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import Any

from ..errors import RailContactError
from ..geometry.track import Track, Wheelset
from ..halfspace.materials import ElasticPair
from ..settings import ContactSettings
from .memory import StepMemory
from .wheelset import WheelsetContact

START_METHOD = "spawn"
"""How worker processes start: a new interpreter (``fork`` would copy a host whose kernel,
FFTW or other threads may hold locks)."""


def worker_python() -> str | None:
    """The Python interpreter the workers are started with: a program of this process's
    Python version (its ``sys.hexversion``, asked with ``-E -s -c``), the first of
    ``sys.executable`` (a Python host), the environment's ``bin/python3`` or ``bin/python``
    (``sys.prefix``), ``sys._base_executable`` and the base installation's
    ``bin/python3`` (``sys.base_prefix``); None when none is. Python embedded in another
    program (an FMU in a C host) may have that program as ``sys.executable``."""
    candidates = [sys.executable,
                  *(os.path.join(sys.prefix, "bin", n) for n in ("python3", "python")),
                  getattr(sys, "_base_executable", ""),
                  os.path.join(sys.base_prefix, "bin", "python3")]
    asked: set[str] = set()
    for exe in candidates:
        if not exe or exe in asked or not (os.path.isfile(exe) and os.access(exe, os.X_OK)):
            continue
        asked.add(exe)
        try:
            out = subprocess.run([exe, "-E", "-s", "-c", "import sys; print(sys.hexversion)"],
                                 capture_output=True, text=True, timeout=60, check=False,
                                 stdin=subprocess.DEVNULL)
        except (OSError, subprocess.SubprocessError):
            continue
        if out.returncode == 0 and out.stdout.strip() == str(sys.hexversion):
            return exe
    return None


@dataclass(frozen=True)
class WheelsetDescription:
    """What a worker process builds a :class:`~railcontact.timestep.WheelsetContact` from
    (the arguments of its constructor; all picklable).

    Attributes
    ----------
    track, wheelset, pair, settings, convention, patch_frame
        As :class:`~railcontact.timestep.WheelsetContact` (SI units; a track and a
        wheelset, or one per side (left, right)); settings None: the defaults.
    """

    track: Track | tuple[Track, Track]
    wheelset: Wheelset | tuple[Wheelset, Wheelset]
    pair: ElasticPair
    settings: ContactSettings | None = None
    convention: str = "railcontact"
    patch_frame: str | None = None

    def build(self) -> WheelsetContact:
        """A new wheelset contact of this description."""
        return WheelsetContact(self.track, self.wheelset, self.pair, self.settings,
                               convention=self.convention, patch_frame=self.patch_frame)


class RemoteError(RailContactError):
    """An error raised in a worker process whose exception could not be sent back as it
    was (not picklable): its type's name, message and the worker's traceback."""


def _portable(exc: BaseException, where: str) -> BaseException:
    """``exc`` as it can be sent to the host: itself when it pickles, else a
    :class:`RemoteError` of its type and message; the worker's traceback as a note."""
    note = f"{where}; the worker's traceback:\n" + "".join(
        traceback.format_exception(type(exc), exc, exc.__traceback__))
    exc.__traceback__ = None
    try:
        pickle.loads(pickle.dumps(exc))
        out = exc
    except Exception:  # noqa: BLE001 - anything the exception's pickling raises
        out = RemoteError(f"{type(exc).__name__}: {exc}")
    out.add_note(note)
    return out


def _build(which: list[int], descriptions: list[WheelsetDescription]
           ) -> tuple[list[WheelsetContact] | None, tuple[bool, BaseException | None]]:
    """The wheelsets of a worker, and the answer to the host: ``(True, None)``, or
    ``(False, exception)`` when one cannot be built."""
    try:
        return [d.build() for d in descriptions], (True, None)
    except BaseException as exc:  # noqa: BLE001 - sent to the host, which raises it
        return None, (False, _portable(exc, f"building wheelsets {[i + 1 for i in which]}"))


def _serve(conn: Connection) -> None:
    """A worker process: receive ``(which, descriptions, reduce)`` and build the wheelsets
    ``which`` (pool indices) from their descriptions, then answer requests until ``None``
    or the pipe closes. (Sent through the pipe rather than as the process's arguments: a
    worker that ends while it reads them makes the host's send fail, where ``spawn`` would
    wait for ever to write arguments larger than the pipe's buffer.)

    A step request is a list of ``solve`` keyword arguments, one per wheelset of this
    worker in ``which`` order (None: that wheelset not stepped); its answer ``(answers,
    received, replied)``: a list of :func:`_solve`'s ``(ok, value, seconds)`` and when
    the request was read and the answer sent (``time.perf_counter()`` [s]). A tuple
    is another request (:func:`_command`: reset, read or set the memories). Interrupts
    (Ctrl+C in a terminal reaches the whole process group) are left to the host, which
    closes the pool."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        which, descriptions, reduce = conn.recv()
    except (EOFError, OSError):  # the host ended
        return
    contacts, answer = _build(which, descriptions)
    conn.send(answer)
    if contacts is None:
        conn.close()
        return
    while True:
        try:
            request = conn.recv()
        except (EOFError, OSError):  # the host ended
            return
        if request is None:
            conn.close()
            return
        if isinstance(request, tuple):
            answer, contacts, descriptions = _command(request, which, contacts,
                                                      descriptions)
            conn.send(answer)
            continue
        received = time.perf_counter()
        answer = [_solve(i, contact, kwargs, reduce)
                  for i, contact, kwargs in zip(which, contacts, request, strict=True)]
        try:
            conn.send((answer, received, time.perf_counter()))
        except Exception as exc:  # noqa: BLE001 - an answer that does not pickle
            conn.send(([(False, _portable(exc, "sending the results"), 0.0)] * len(which),
                       received, time.perf_counter()))


def _solve(i: int, contact: WheelsetContact, kwargs: Mapping[str, Any] | None,
           reduce: Callable[[Any], Any] | None) -> tuple[bool, Any, float]:
    """Wheelset ``i``'s step (pool index) of ``kwargs`` (None: not stepped): ``(True,
    its result or what ``reduce`` makes of it (None when not stepped), the wall time of
    the solve [s])``, or ``(False, the exception as it can be sent, the wall time)``."""
    if kwargs is None:
        return True, None, 0.0
    t0 = time.perf_counter()
    try:
        r = contact.solve(**kwargs)
        return True, r if reduce is None else reduce(r), time.perf_counter() - t0
    except Exception as exc:  # noqa: BLE001 - the host raises or returns it
        return False, _portable(exc, f"wheelset {i + 1}"), time.perf_counter() - t0


def _command(request: tuple, which: list[int], contacts: list[WheelsetContact],
             descriptions: list[WheelsetDescription]
             ) -> tuple[Any, list[WheelsetContact], list[WheelsetDescription]]:
    """A worker's answer to a request other than a step (a tuple, its name first), and
    its wheelsets and their descriptions after it:

    - ``("reset", descriptions)``: the wheelsets built anew (from new descriptions unless
      None); the answer of :func:`_build` (the wheelsets unchanged when it fails);
    - ``("memory",)``: ``(True, memories)``, the wheelsets' step memories
      (:attr:`WheelsetContact.memory`) in ``which`` order;
    - ``("set_memory", memories)``: each wheelset's memory set (None: forgotten,
      :meth:`WheelsetContact.reset`); ``(True, None)``.

    An error is answered ``(False, exception)``."""
    name = request[0]
    if name == "reset":
        wanted = request[1] or descriptions
        built, answer = _build(which, wanted)
        return (answer, contacts, descriptions) if built is None else (answer, built, wanted)
    try:
        if name == "memory":
            return (True, [c.memory for c in contacts]), contacts, descriptions
        if name == "set_memory":
            for c, m in zip(contacts, request[1], strict=True):
                if m is None:
                    c.reset()
                else:
                    c.memory = m
            return (True, None), contacts, descriptions
        raise RailContactError(f"unknown request {name!r} to a wheelset pool's worker")
    except Exception as exc:  # noqa: BLE001 - sent to the host, which raises it
        return ((False, _portable(exc, f"{name} of wheelsets {[i + 1 for i in which]}")),
                contacts, descriptions)


@contextmanager
def _without_main() -> Iterator[None]:
    """Workers started within do not import the host's main module (``spawn`` runs it
    again in the worker as ``__mp_main__``: a script without the ``if __name__ ==
    "__main__"`` guard would run again in each)."""
    given = multiprocessing.spawn.get_preparation_data

    def preparation(name: str) -> dict:
        data = given(name)
        data.pop("init_main_from_name", None)
        data.pop("init_main_from_path", None)
        return data

    with _SPAWN_LOCK:
        multiprocessing.spawn.get_preparation_data = preparation
        try:
            yield
        finally:
            multiprocessing.spawn.get_preparation_data = given


_SPAWN_LOCK = threading.Lock()


def _stop(processes: list, connections: list[Connection], timeout: float = 5.0) -> None:
    """End the workers: ask, wait up to ``timeout`` [s] each, then terminate."""
    for conn in connections:
        try:
            conn.send(None)
        except (OSError, ValueError, BrokenPipeError):
            pass
    for p in processes:
        p.join(timeout)
        if p.is_alive():
            p.terminate()
            p.join(timeout)
    for conn in connections:
        conn.close()


class WheelsetPool:
    """N wheelsets, each in the same worker process step after step, stepped at once.

    Parameters
    ----------
    descriptions
        One :class:`WheelsetDescription` per wheelset (pool index ``i`` = its position).
    processes
        Processes stepping the wheelsets (worker processes, and this one with ``here``);
        None: ``os.cpu_count()``; at most the number of wheelsets. Wheelset ``i`` runs in
        process ``i mod processes`` (process 0 this one with ``here``).
    reduce
        None: :meth:`step` returns each wheelset's
        :class:`~railcontact.timestep.WheelsetResult` (its values as in-process; about
        1 MB a wheelset with its patches' geometry, pickled in the worker and read here
        every step). Else a picklable function (defined at a module's top level) applied
        to each result in the worker; :meth:`step` returns its values: what the host
        needs, sent instead of the whole result.
    main
        Whether the workers import the host's main module first, as ``spawn`` does (needed
        when ``descriptions`` or ``reduce`` refer to it). False: they do not, so that a
        host script without the ``if __name__ == "__main__"`` guard (or a host whose main
        module is none of the pool's concern, as an FMU's) is not run again in each.
    timeout
        The longest wait [s] for a worker's answer to a step or another request after
        the pool has started; None: no limit. A worker that takes longer is taken as
        hung: the pool is closed (its workers asked to end, then terminated) and a
        :class:`RailContactError` raised.
    here
        Whether this process steps the first share of the wheelsets itself (wheelsets
        ``i`` with ``i mod processes = 0``, built here), while the ``processes - 1``
        worker processes step theirs: one process fewer than cores to keep busy, and no
        round trip for that share; its results and errors are those a worker gives (the
        same solve and ``reduce``). False: every wheelset in a worker process.
    python
        The Python interpreter the workers run (``multiprocessing``'s ``set_executable``
        for the ``spawn`` start method, a setting of the process); None: as it is
        (``sys.executable`` unless set before). In a program that embeds Python, give
        :func:`worker_python`.

    Raises
    ------
    RailContactError
        No wheelsets, ``processes < 1``, or a wheelset that cannot be built (then the
        worker's exception itself, e.g. a :class:`RailContactError` of the settings).

    Notes
    -----
    Use as a context manager or call :meth:`close`; workers end with the host process as
    well. The pool is used from one thread at a time.
    """

    def __init__(self, descriptions: Sequence[WheelsetDescription],
                 processes: int | None = None,
                 reduce: Callable[[Any], Any] | None = None,
                 python: str | None = None, main: bool = True,
                 timeout: float | None = None, here: bool = False) -> None:
        n = len(descriptions)
        if n == 0:
            raise RailContactError("a wheelset pool needs at least one wheelset")
        _check_descriptions(descriptions)
        if reduce is not None:
            try:
                pickle.dumps(reduce)
            except Exception as exc:  # noqa: BLE001 - whatever pickling raises
                raise RailContactError(
                    f"reduce must be a function defined at a module's top level (sent to "
                    f"the worker processes by name), got {reduce!r}") from exc
        p = (os.cpu_count() or 1) if processes is None else processes
        if p < 1:
            raise RailContactError(f"processes must be at least 1, got {p}")
        p = min(p, n)
        if timeout is not None and not timeout > 0:
            raise RailContactError(f"timeout must be above 0 s or None, got {timeout!r}")
        self.count = n
        """Number of wheelsets."""
        self.timeout = timeout
        """The longest wait for a worker's answer [s] (None: no limit)."""
        self.shares = [[i for i in range(n) if i % p == j] for j in range(p)]
        """The wheelsets (pool indices) of each process (the first this one's with
        ``here``)."""
        self.here = bool(here)
        """Whether this process steps the first share itself."""
        self._remote = self.shares[1:] if self.here else self.shares
        self._reduce = reduce
        self._local: list[WheelsetContact] = []  # the first share's wheelsets with here
        self._local_descriptions: list[WheelsetDescription] = []
        self.seconds: list[float] = [0.0] * n
        """Wall time of each wheelset's solve in its process at the last step [s]."""
        self.sent = 0.0
        """When the last step's requests were sent (``time.perf_counter()`` [s])."""
        self.spans: list[tuple[float, float, float]] = [(0.0, 0.0, 0.0)] * len(self._remote)
        """Per worker process (in :attr:`shares` order) at the last step: when its
        request arrived, when it sent its answer (its ``time.perf_counter()``: on Linux
        the host's clock as well) and when the answer was read here [s]; with
        :attr:`sent` and :attr:`seconds`, where a step's time went (sending, waking,
        solving, answering)."""
        ctx = multiprocessing.get_context(START_METHOD)
        if python is not None and python != multiprocessing.spawn.get_executable():
            ctx.set_executable(python)
        self._processes: list = []
        self._connections: list[Connection] = []
        self._closed = False
        self._finalizer = weakref.finalize(self, _stop, self._processes, self._connections)
        try:
            if self.here:
                self._local_descriptions = [descriptions[i] for i in self.shares[0]]
                self._local = [d.build() for d in self._local_descriptions]
            for j in range(len(self._remote)):
                here, there = ctx.Pipe()
                proc = ctx.Process(target=_serve, name=f"railcontact-wheelsets-{j}",
                                   args=(there,), daemon=True)
                with _without_main() if not main else nullcontext():
                    proc.start()
                there.close()
                self._processes.append(proc)
                self._connections.append(here)
            for j, which in enumerate(self._remote):
                try:
                    self._connections[j].send((which, [descriptions[i] for i in which],
                                               reduce))
                except OSError as exc:
                    self._processes[j].join(1.0)
                    raise RailContactError(
                        f"worker process {j + 1} of the wheelset pool ended as it started "
                        f"(exit code {self._processes[j].exitcode})") from exc
            for j, conn in enumerate(self._connections):
                ok, exc = self._receive(j, conn)
                if not ok:
                    raise exc
        except BaseException:
            self.close()
            raise

    @property
    def processes(self) -> int:
        """Number of processes stepping the wheelsets (this one included with
        :attr:`here`)."""
        return len(self.shares)

    def _receive(self, j: int, conn: Connection, timeout: float | None = None) -> Any:
        """Worker ``j``'s answer; a :class:`RailContactError` when it ended, or when it
        has not answered within ``timeout`` [s] (None: no limit)."""
        if timeout is not None and not conn.poll(timeout):
            raise RailContactError(
                f"worker process {j + 1} of the wheelset pool did not answer within "
                f"{timeout:g} s (the pool's timeout); the pool is closed") from TimeoutError()
        try:
            return conn.recv()
        except (EOFError, OSError) as exc:
            proc = self._processes[j]
            proc.join(1.0)
            raise RailContactError(
                f"worker process {j + 1} of the wheelset pool ended (exit code "
                f"{proc.exitcode}); the pool is closed") from exc

    def step(self, inputs: Sequence[Mapping[str, Any] | None], errors: str = "raise"
             ) -> list[Any]:
        """Step every wheelset once.

        Parameters
        ----------
        inputs
            Per wheelset (pool order) the keyword arguments of
            :meth:`WheelsetContact.solve <railcontact.timestep.WheelsetContact.solve>`
            (``pose``, ``loads`` or ``vertical``, ``kinematics``, ``time`` [s], ...); None:
            the wheelset is not stepped (its result None, its memory unchanged).
        errors
            ``"raise"``: a wheelset's error is raised (below). ``"return"``: it takes the
            wheelset's place in the list returned, the other wheelsets' results beside it.

        Returns
        -------
        list
            Per wheelset its :class:`~railcontact.timestep.WheelsetResult`, or what the
            pool's ``reduce`` makes of it (with ``errors="return"``, the exception of a
            wheelset whose solve raised one). :attr:`seconds`: the solves' wall times [s].

        Raises
        ------
        Exception
            The exception a wheelset's solve raised in its worker (its type and message,
            the worker's traceback as a note; the first failing wheelset's); the other
            wheelsets of the step are solved and the pool keeps working.
        RailContactError
            A closed pool, a wrong number of inputs, or a worker process that ended
            (whatever ``errors``; the pool is closed).
        """
        if errors not in ("raise", "return"):
            raise RailContactError(f'errors must be "raise" or "return", got {errors!r}')
        if self._closed:
            raise RailContactError("the wheelset pool is closed")
        if len(inputs) != self.count:
            raise RailContactError(f"{self.count} wheelsets' inputs expected, got "
                                   f"{len(inputs)}")
        # every request pickled before any is sent: an input that does not pickle leaves
        # the workers in step with the host
        payloads = [pickle.dumps([None if inputs[i] is None else dict(inputs[i])
                                  for i in which], pickle.HIGHEST_PROTOCOL)
                    for which in self._remote]
        out: list[Any] = [None] * self.count
        failed: list[tuple[int, BaseException]] = []
        ended: RailContactError | None = None
        self.sent = time.perf_counter()
        try:
            for j, payload in enumerate(payloads):
                try:
                    self._connections[j].send_bytes(payload)
                except (OSError, ValueError) as exc:
                    raise RailContactError(f"worker process {j + 1} of the wheelset pool "
                                           "cannot be reached; the pool is closed") from exc
            if self.here:  # (while the workers solve theirs)
                for i, contact in zip(self.shares[0], self._local, strict=True):
                    ok, out[i], self.seconds[i] = _solve(i, contact, inputs[i], self._reduce)
                    if not ok:
                        failed.append((i, out[i]))
            for j, which in enumerate(self._remote):
                try:
                    answer, *span = self._receive(j, self._connections[j], self.timeout)
                except RailContactError as exc:
                    ended = ended or exc
                    continue
                self.spans[j] = (span[0], span[1], time.perf_counter())
                for i, (ok, value, secs) in zip(which, answer, strict=True):
                    self.seconds[i] = secs
                    out[i] = value
                    if not ok:
                        failed.append((i, value))
        except BaseException:  # an interrupted round trip: the workers are out of step
            self.close()
            raise
        if ended is not None:
            self.close()
            raise ended
        if failed and errors == "raise":
            raise min(failed, key=lambda e: e[0])[1]
        return out

    def reset(self, descriptions: Sequence[WheelsetDescription] | None = None) -> None:
        """Build every wheelset anew in its worker process (no warm-start memory), from
        ``descriptions`` (one per wheelset) or from those it was built from; the worker
        processes, their loaded kernels and FFT plans stay.

        Raises
        ------
        RailContactError
            For descriptions that are not one :class:`WheelsetDescription` per wheelset
            (before any wheelset is reset).
        Exception
            A wheelset that cannot be built (the worker's exception; the wheelsets of
            that worker stay as they were).
        """
        if descriptions is not None:
            if len(descriptions) != self.count:
                raise RailContactError(f"{self.count} wheelset descriptions expected, got "
                                       f"{len(descriptions)}")
            _check_descriptions(descriptions)  # (before any wheelset is reset)
        self._check_open()
        error = None
        if self.here:
            wanted = (self._local_descriptions if descriptions is None
                      else [descriptions[i] for i in self.shares[0]])
            try:
                local = [d.build() for d in wanted]
            except Exception as exc:  # noqa: BLE001 - raised after the workers' reset
                error = exc
            else:
                self._local, self._local_descriptions = local, wanted
        self._ask([("reset", None if descriptions is None else
                    [descriptions[i] for i in which]) for which in self._remote])
        if error is not None:
            raise error

    def memories(self) -> list[StepMemory]:
        """Each wheelset's step memory (:attr:`WheelsetContact.memory
        <railcontact.timestep.WheelsetContact.memory>`, where its next step starts), read
        in its process; pool order."""
        self._check_open()
        out: list[Any] = [None] * self.count
        if self.here:
            for i, contact in zip(self.shares[0], self._local, strict=True):
                out[i] = contact.memory
        for which, values in zip(self._remote, self._ask([("memory",)] * len(self._remote)),
                                 strict=True):
            for i, m in zip(which, values, strict=True):
                out[i] = m
        return out

    def set_memories(self, memories: Sequence[StepMemory | None]) -> None:
        """Set each wheelset's step memory in its process (pool order; None: the
        wheelset forgets its previous steps, :meth:`WheelsetContact.reset
        <railcontact.timestep.WheelsetContact.reset>`): its next step starts from it as
        after the step that left it."""
        if len(memories) != self.count:
            raise RailContactError(f"{self.count} wheelsets' memories expected, got "
                                   f"{len(memories)}")
        for i, m in enumerate(memories):
            if m is not None and not isinstance(m, StepMemory):
                raise RailContactError(f"wheelset {i + 1}: a StepMemory or None expected, "
                                       f"got {type(m).__name__}")
        self._check_open()
        if self.here:
            for i, contact in zip(self.shares[0], self._local, strict=True):
                if memories[i] is None:
                    contact.reset()
                else:
                    contact.memory = memories[i]
        self._ask([("set_memory", [memories[i] for i in which]) for which in self._remote])

    def _check_open(self) -> None:
        if self._closed:
            raise RailContactError("the wheelset pool is closed")

    def _ask(self, requests: list[tuple]) -> list[Any]:
        """Send each worker process its request (:func:`_command`) and return their
        answers' values; the first worker's exception raised after all have answered."""
        if self._closed:
            raise RailContactError("the wheelset pool is closed")
        try:
            for j, request in enumerate(requests):
                self._connections[j].send(request)
            answers = [self._receive(j, conn, self.timeout)
                       for j, conn in enumerate(self._connections)]
        except BaseException:  # a worker ended or the round trip broke: out of step
            self.close()
            raise
        first = next((value for ok, value in answers if not ok), None)
        if first is not None:
            raise first
        return [value for _, value in answers]

    def close(self) -> None:
        """End the worker processes (idempotent)."""
        self._closed = True
        self._local = []
        self._finalizer()

    def __enter__(self) -> WheelsetPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __len__(self) -> int:
        return self.count

    @property
    def alive(self) -> bool:
        """Whether every worker process runs."""
        return not self._closed and all(p.is_alive() for p in self._processes)



def _check_descriptions(descriptions: Sequence[WheelsetDescription]) -> None:
    """Raise a :class:`RailContactError` naming the first of ``descriptions`` that is not
    a :class:`WheelsetDescription` (counted from 1)."""
    for i, d in enumerate(descriptions):
        if not isinstance(d, WheelsetDescription):
            raise RailContactError(f"wheelset {i + 1}: a WheelsetDescription expected, "
                                   f"got {type(d).__name__}")

__all__ = ["START_METHOD", "RemoteError", "WheelsetDescription", "WheelsetPool",
           "worker_python"]
