"""Run one function over many items: in-process, local processes, or Dask.

The three back ends return the same list, in the order of the items, so a
result never depends on how many workers computed it (each item's
randomness must come from the item itself, see :func:`hesspipe.core.seeds.derive_seed`).

* ``workers=1``: a plain loop in this process (no pickling, easy debugging).
* ``workers=N`` (default: all cores): :class:`concurrent.futures.ProcessPoolExecutor`.
* ``scheduler="tcp://host:8786"``: the items are submitted to an existing
  Dask distributed cluster (optional dependency, ``pip install hesspipe[dask]``);
  its workers must have hesspipe installed.

`func` and the items must be picklable for the last two (a module-level
function, or :func:`functools.partial` of one).
"""

from __future__ import annotations

import multiprocessing
import os
import re
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Callable, Sequence

from ..core.errors import HesspipeError
from ..core.progress import progress_bar

#: How often a worker looks for the process that started it, s.
PARENT_POLL_S = 0.5


def default_workers() -> int:
    """Number of cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def _mp_context():
    # fork is cheapest (no re-import of scipy/control per worker) but unsafe
    # once this process runs threads (a Dask client, a tqdm monitor): then
    # forkserver, which starts workers from a clean single-threaded process.
    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        return multiprocessing.get_context("forkserver")
    return multiprocessing.get_context("spawn")


def check_workers(workers) -> int:
    """Return `workers` if it is an integer >= 0 (the one rule; callers check early with it).

    Parameters
    ----------
    workers : int
        Number of worker processes, 0 for all cores (as the TOML's ``workers = 0``); a bool
        is refused.

    Returns
    -------
    int
        `workers`, unchanged.

    Raises
    ------
    HesspipeError
        Naming ``workers``, if it is not an integer >= 0.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise HesspipeError(f"workers: expected an integer >= 0 (0: all cores), got {workers!r}")
    return workers


def run_batch(func: Callable, items: Sequence, *, workers: int | None = None,
              scheduler: str | None = None, desc: str = "batch", unit: str = "item",
              progress: bool | None = None, connect_timeout: float = 10.0) -> list:
    """Return ``[func(item) for item in items]``, computed in parallel.

    Parameters
    ----------
    func : callable
        Applied to each item. Exceptions it raises propagate (wrap it if one
        item's failure must not stop the batch).
    items : sequence
    workers : int, optional
        Local worker processes (None or 0: all cores; 1 runs in this process).
        Ignored with `scheduler`.
    scheduler : str, optional
        Address of a Dask distributed scheduler (``tcp://host:port``).
    desc, unit : str
        Progress-bar label and item name.
    progress : bool, optional
        Force the progress bar on/off (default: only on a terminal).
    connect_timeout : float
        Seconds to wait for the Dask scheduler.

    Raises
    ------
    HesspipeError
        Bad `workers`, Dask not installed, or the scheduler unreachable.
    """
    items = list(items)
    if scheduler:
        return _run_dask(func, items, scheduler, desc, unit, progress, connect_timeout)
    if workers is None or check_workers(workers) == 0:
        workers = default_workers()
    workers = min(workers, max(len(items), 1))
    results: list = [None] * len(items)
    with progress_bar(len(items), desc, enable=progress, unit=unit) as bar:
        if workers == 1:
            for i, item in enumerate(items):
                results[i] = func(item)
                bar.update(1)
            return results
        context = _mp_context()
        held = _STOPS if _forks_here(context) else frozenset()
        pool = ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                   initializer=_worker_init, initargs=(held,))
        try:
            # The pool forks its workers on the first submit. A stop arriving meanwhile would
            # run its handler inside an at-fork hook (logging's), where Python prints it as
            # "Exception ignored" with a traceback and goes on; held, it is delivered when the
            # mask is put back, here, and stops the batch like any other.
            previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
            try:
                futures = {pool.submit(func, item): i for i, item in enumerate(items)}
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, previous)
            for future in as_completed(futures):
                results[futures[future]] = future.result()
                bar.update(1)
        except BaseException:
            # Interrupted (Ctrl-C, SIGTERM via hesspipe.cli) or an item failed: stop the
            # workers now rather than wait for their items, and leave no process behind.
            _terminate(pool)
            raise
        pool.shutdown(wait=True)
    return results


#: The stop signals held while a pool forks its workers (see :func:`run_batch`).
_STOPS = frozenset({signal.SIGTERM, signal.SIGINT})


def _forks_here(context) -> bool:
    """True if `context` forks this very thread (only then do at-fork hooks run in it; a
    signal mask is a thread's own, so only the main thread's, where handlers run, matters)."""
    return (context.get_start_method() == "fork"
            and threading.current_thread() is threading.main_thread())


def _worker_init(held: frozenset = frozenset()) -> None:
    """Worker processes die quietly on SIGTERM (a forked worker inherits the CLI's
    handler, which would print a traceback), and with the process that started them.

    Parameters
    ----------
    held : frozenset of int
        Signals the parent held while it forked (inherited blocked); released here, after
        SIGTERM's default action is back.
    """
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, held)
    # Killed outright (SIGKILL), the parent cannot stop its pool: the workers, blocked on a
    # queue whose other end they hold themselves, would wait for ever and keep its stdout open.
    parent = os.getppid()

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="hesspipe-parent-watch", daemon=True).start()


def _terminate(pool: ProcessPoolExecutor) -> None:
    """Shut `pool` down without waiting for running items: terminate and reap its workers."""
    # ProcessPoolExecutor has no public way to stop running items before Python 3.14
    # (terminate_workers); its process table is the documented-in-source fallback.
    processes = list(getattr(pool, "_processes", {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)   # shutdown() forgets both
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        proc.join(timeout=5)
        if proc.is_alive():
            proc.kill()
            proc.join(timeout=5)
    # Let the pool's manager thread see its workers gone and close its wake-up pipe before
    # the interpreter exits: on Python 3.11 the exit hook of concurrent.futures otherwise
    # races that close and can write to the closed pipe ("Exception ignored ... Bad file
    # descriptor" after "hesspipe: terminated", 1 of 3 CI runs of the SIGTERM test).
    if manager is not None:
        manager.join(timeout=5)


#: A Dask scheduler address: optional protocol, host (name, IPv4 or [IPv6]) and port;
#: or an in-process cluster's inproc:// address.
_ADDRESS = re.compile(r"^(?:(?:tcp|tls|ws|wss|ucx)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9.-]+):(\d{1,5})$")


def check_scheduler_address(address: str, name: str = "scheduler") -> str:
    """Return `address` if it reads like ``tcp://HOST:PORT``; raise at once otherwise.

    Parameters
    ----------
    address : str
        Dask scheduler address: optional protocol (``tcp``, ``tls``, ``ws``,
        ``wss``, ``ucx``), host (name, IPv4 or ``[IPv6]``) and port 1-65535;
        or an in-process ``inproc://...`` address. Surrounding spaces are
        stripped.
    name : str
        How the caller calls the setting, for the message.

    Returns
    -------
    str
        The stripped address (nothing is contacted).

    Raises
    ------
    HesspipeError
        Naming `name`, if the address does not have that form.
    """
    text = address.strip() if isinstance(address, str) else ""
    if text.startswith("inproc://") and len(text) > len("inproc://"):
        return text
    m = _ADDRESS.match(text)
    if m is None or not 1 <= int(m.group(2)) <= 65535:
        raise HesspipeError(f"{name}: expected a Dask scheduler address like tcp://HOST:PORT "
                            f"(port 1-65535), got {address!r}")
    return text


def _connect(address: str, timeout: float):
    """A Dask Client for `address`, or HesspipeError after `timeout` s.

    distributed's own timeout covers the TCP connection but not its handshake: a port
    where something other than a Dask scheduler listens accepts the connection and never
    answers. The client is made in a daemon thread so the wait is bounded either way.
    """
    from distributed import Client

    box: dict = {}

    def make():
        try:
            box["client"] = Client(address, timeout=f"{timeout}s", set_as_default=False)
        except BaseException as exc:  # noqa: BLE001 - reported below, in the caller's thread
            box["error"] = exc

    thread = threading.Thread(target=make, name="hesspipe-dask-connect", daemon=True)
    thread.start()
    thread.join(timeout + 2.0)
    if "client" in box:
        return box["client"]
    why = (f"{type(box['error']).__name__}: {box['error']}" if "error" in box
           else f"no Dask answer within {timeout:g} s; is a Dask scheduler listening there?")
    raise HesspipeError(f"scheduler {address}: cannot connect to a Dask scheduler ({why})")


def _run_dask(func, items, address, desc, unit, progress, timeout) -> list:
    address = check_scheduler_address(address)
    try:
        from distributed import as_completed as dask_completed
    except ImportError:
        raise HesspipeError(f"scheduler {address}: Dask distributed is not installed; "
                            "install it with pip install 'hesspipe[dask]'") from None
    client = _connect(address, timeout)
    with client, progress_bar(len(items), desc, enable=progress, unit=unit) as bar:
        # pure=False: identical items (two copies of a file) are still two tasks.
        futures = client.map(func, items, pure=False)
        for _ in dask_completed(futures, loop=client.loop):
            bar.update(1)
        return client.gather(futures)
