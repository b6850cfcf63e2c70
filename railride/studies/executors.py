"""Where the runs of a study go and where they are kept: executors and the run table.

An executor runs chunks of cases (`railride.studies.sweep.evaluate` on each) and yields their rows:
`LocalExecutor` on this machine, each batch over every core and the next chunk stepping while
the last one's rows are made;
`ProcessExecutor` on worker processes of this machine (the chunks' Python work in parallel too);
`DaskExecutor` on a dask.distributed cluster. `RunTable` keeps every finished run in a CSV
file rewritten atomically as chunks finish, so an interrupted study resumes where it stopped
(`railride.studies.sweep.run_cases`).
"""

from __future__ import annotations

import json
import math
import os
import socket
import time
from pathlib import Path

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride._io import atomic_write


# -- executors ---------------------------------------------------------------------------------
#: samples per compiled batch (a study's chunk, `railride.studies.sweep.run_cases`): bounds the
#: memory of the time histories (about 5 MB a sample for 10 s at 1 kHz)
CHUNK = 32


def chunks_ahead(threads: int | None = None, rows_beside: bool = True) -> int:
    """The chunks a `LocalExecutor` runs beside the one whose rows are being made, by default:
    enough for the chunks that step at once to hold every one of ``threads`` (default numba's
    thread count). A chunk of `CHUNK` runs on the lane stepper steps on one thread per group of
    `railride.engine.lanes.LANES` runs (`railride.run.cores`): 4 threads, so 16 threads want
    four chunks stepping, where one chunk ahead held at most 8 (docs/performance.md).
    ``rows_beside``: one chunk more, whose rows are made while the others step (at least 1);
    False: none more (a design's chunks of 20 s runs, whose memory that would double on 2
    cores, for nothing there: docs/performance.md)."""
    import numba

    from railride.engine.kernels import threads_for
    from railride.engine.lanes import LANES

    threads = int(numba.get_num_threads()) if threads is None else int(threads)
    per_chunk = threads_for(-(-CHUNK // LANES), threads)  # as `railride.run.simulation.threads_used`
    stepping = -(-threads // per_chunk)
    return max(1, stepping) if rows_beside else max(0, stepping - 1)


class LocalExecutor:
    """Chunks run in this process, each chunk's batch over every core, and ``ahead`` chunks
    run beside the one whose rows are being made: a chunk's serial work in Python (its input
    tables, metrics, comfort and rows) then overlaps the stepping of the next, which the
    compiled stepper does without the GIL. One batch steps at a time where each fills numba's
    threads (`railride.run.cores`): batches that stepped beside each other shared the cores,
    ended together and then made their rows together while no core stepped. The chunks step on
    the caller's numba thread count. Rows come back in the order of the chunks, as they would one
    after another. At most ``ahead`` + 1 chunks are in memory at once. ``ahead``: default
    `chunks_ahead` of numba's thread count (1 on up to 4 threads, 4 on 16; with ``rows_beside``
    False, 0 and 3); 0: one after another."""

    name = "local"

    def __init__(self, ahead: int | None = None, rows_beside: bool = True):
        self.ahead = chunks_ahead(rows_beside=rows_beside) if ahead is None else max(0, int(ahead))

    def bounded(self, chunk_bytes: float) -> "LocalExecutor":
        """This executor with no more chunks in flight than the memory limit holds
        (`railride.limits.max_memory`: half the machine's by default), each chunk taking
        ``chunk_bytes``; at least one chunk (whose own size each run checks)."""
        from railride.limits import max_memory

        fit = int(max_memory() // max(float(chunk_bytes), 1.0))  # chunks in flight that fit
        return LocalExecutor(max(0, min(self.ahead, fit - 1)))

    def map(self, fn, chunks):
        if self.ahead == 0:
            for i, chunk in enumerate(chunks):
                yield i, fn(chunk)
            return
        from collections import deque
        from concurrent.futures import ThreadPoolExecutor

        import numba

        # numba's thread count is the thread's own (`numba.set_num_threads`, e.g. --workers N):
        # the chunks' threads take the caller's, where they would start with every core
        pool = ThreadPoolExecutor(
            self.ahead + 1,
            thread_name_prefix="railride-chunk",
            initializer=numba.set_num_threads,
            initargs=(numba.get_num_threads(),),
        )
        pending: deque = deque()
        try:
            for i, chunk in enumerate(chunks):
                pending.append((i, pool.submit(fn, chunk)))
                if len(pending) > self.ahead:
                    k, job = pending.popleft()
                    yield k, job.result()
            while pending:
                k, job = pending.popleft()
                yield k, job.result()
        finally:
            # stopped early (Ctrl-C, an error, a closed generator): the chunks not begun are
            # dropped; one already stepping ends in its thread, its rows unused
            for _, job in pending:
                job.cancel()
            pool.shutdown(wait=False, cancel_futures=True)

    def close(self):
        pass


class ProcessExecutor:
    """Chunks on ``processes`` worker processes of this machine, each with its share of the cores
    for its batches (numba threads = cores // processes, at least 1). A chunk's Python work
    (its input tables, metrics, comfort and rows) holds the GIL, so threads can overlap it with
    the stepping but not split it; processes run it in parallel too, which is what many cores
    need (docs/performance.md). Workers are started fresh (spawn: a fork would copy numba's
    running thread pool), which costs each a second or two of imports, so this pays for
    studies of hundreds of runs and more. Rows come back as chunks finish, as on Dask."""

    name = "processes"

    def __init__(self, processes: int):
        from railride import validation

        self.processes = validation.integer("processes", processes, 1, 1024, "worker processes")
        self._pool = None

    def _start(self):
        if self._pool is None:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            import numba

            cores = int(numba.config.NUMBA_NUM_THREADS)
            threads = max(1, cores // self.processes)
            self._pool = ProcessPoolExecutor(
                self.processes,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_worker_threads,
                initargs=(threads,),
            )
        return self._pool

    def map(self, fn, chunks):
        from concurrent.futures import as_completed

        pool = self._start()
        futures = {pool.submit(fn, chunk): i for i, chunk in enumerate(chunks)}
        try:
            for fut in as_completed(futures):
                yield futures.pop(fut), fut.result()
        finally:  # stopped early (an error, Ctrl-C): drop what has not begun
            for fut in futures:
                fut.cancel()

    def close(self):
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None


def _worker_threads(threads: int) -> None:
    """A `ProcessExecutor` worker's start: its share of the cores for its batches."""
    import numba

    numba.set_num_threads(threads)


class DaskExecutor:
    """Chunks run as tasks on a dask.distributed cluster (``address`` tcp://host:port, or the
    ``scheduler_file`` that ``dask scheduler --scheduler-file`` writes). Needs the optional
    extra: pip install "railride[distributed]"; every worker imports the same railride.

    One chunk is one task and one compiled batch, on its share of the worker machine's cores:
    numba's thread count there (NUMBA_NUM_THREADS, every core by default) divided by the Dask
    threads of all the workers on that machine, at least 1. So batches do not multiply Dask's
    threads: one ``dask worker --nthreads 1`` per machine gives each batch every core, a default
    ``dask worker`` (a thread per core) one core to each of its batches (docs/distributed.md).

    ``address`` is tcp://host:port (or host:port), ws://host:port, tls:// or wss:// with the
    cluster's certificates (``security``, a distributed.Security, or Dask's configuration), or
    the inproc:// address of a scheduler in this process. Every other address fails fast,
    before a Client exists (a half-made Client hangs for 20 s as it is collected): an unknown
    or unusable scheme, TLS without certificates, a refused port, a host that does not answer
    within `PROBE_SECONDS`, a port that accepts but does not speak Dask within
    `HANDSHAKE_SECONDS` (a dashboard's); a scheduler file that does not appear within
    ``timeout`` or has no address. Each is a ValueError naming the address (or file) and what
    is allowed. `map` yields (chunk
    index, rows) in the order chunks finish; a chunk lost with a dead worker is run again by the
    scheduler."""

    name = "dask"

    def __init__(
        self,
        address: str | None = None,
        scheduler_file: str | None = None,
        timeout: float = 10.0,
        security=None,
    ):
        try:
            from distributed import Client
        except ImportError:
            raise InputError('the Dask executor needs dask.distributed: pip install "railride[distributed]"') from None
        if (address is None) == (scheduler_file is None):
            raise InputError("give a scheduler address (tcp://host:port) or a scheduler file")
        if scheduler_file is not None:
            address = self._address_from_file(scheduler_file, timeout)
        assert address is not None  # one of the two was given, checked above
        self.address = address
        where = f"address = {address!r}" + ("" if scheduler_file is None else f" (from {scheduler_file})")
        security = _security(address, security, where)
        _reach(address, timeout, security, where)
        try:
            # not the default client: this executor's tasks only, the caller's Dask code untouched
            self.client = Client(address, timeout=timeout, set_as_default=False, security=security)
        except Exception as exc:  # answered the handshake, then failed: not a scheduler after all
            raise InputError(
                f"{where}: cannot reach the Dask scheduler at {address} within {timeout:g} s: "
                f"{type(exc).__name__}: {_one_line(exc)}"
            ) from None

    @staticmethod
    def _address_from_file(path, timeout: float) -> str:
        """The address in a scheduler file, waiting up to ``timeout`` for the scheduler to write it
        (distributed's own Client would wait for a missing file forever)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                address = json.loads(Path(path).read_text())["address"]
                if isinstance(address, str) and address:
                    return address
                problem = f"address = {address!r}"
            except FileNotFoundError:
                problem = "no such file"
            except (OSError, ValueError, TypeError, KeyError) as exc:
                problem = f"not a Dask scheduler file ({type(exc).__name__}: {exc})"
            if time.monotonic() >= deadline:
                raise InputError(f"scheduler file {str(path)!r}: {problem} after {timeout:g} s")
            time.sleep(0.1)

    def map(self, fn, chunks):
        import uuid

        from distributed import as_completed
        from distributed.comm import get_address_host

        # the Dask threads on each machine (by host address), so a task knows its share
        nthreads = self.client.nthreads()
        per_host: dict[str, int] = {}
        for worker, n in nthreads.items():
            host = get_address_host(worker)
            per_host[host] = per_host.get(host, 0) + n
        shares = {worker: per_host[get_address_host(worker)] for worker in nthreads}
        tag = uuid.uuid4().hex[:8]
        futures = {
            self.client.submit(self._run_chunk, fn, shares, chunk, key=f"railride-chunk-{tag}-{i}"): i
            for i, chunk in enumerate(chunks)
        }
        try:
            for fut in as_completed(futures, loop=self.client.loop):
                i = futures.pop(fut)
                yield i, fut.result()
        finally:  # stopped early (an error, Ctrl-C): drop what has not finished
            if futures:
                self.client.cancel(list(futures))

    @staticmethod
    def _run_chunk(fn, shares: dict, chunk):
        """On a worker: ``fn(chunk)`` on numba's thread count divided by the Dask threads on this
        machine (``shares``, as the map started; this worker's own for a worker that joined
        later). The thread count is per thread (`numba.set_num_threads`), so restored after."""
        import numba
        from distributed import get_worker

        worker = get_worker()
        share = shares.get(worker.address, worker.state.nthreads)
        before = numba.get_num_threads()
        numba.set_num_threads(max(1, numba.config.NUMBA_NUM_THREADS // max(1, share)))  # type: ignore[attr-defined]
        try:
            return fn(chunk)
        finally:
            numba.set_num_threads(before)

    def close(self):
        self.client.close()


#: seconds for a scheduler's host to accept a connection: a TCP connect on a network takes
#: milliseconds, so a host that has not answered in this time is down or behind a firewall
PROBE_SECONDS = 3.0
#: seconds for a port that accepted to answer Dask's handshake (a scheduler answers at once)
HANDSHAKE_SECONDS = 5.0
#: the addresses a DaskExecutor can use, for the errors
ALLOWED = (
    "allowed: tcp://host:port (or host:port), ws://host:port, tls:// or wss:// with the cluster's "
    "certificates, or the inproc:// address of a scheduler in this process"
)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _security(address: str, security, where: str):
    """The client's security for ``address``: ``security`` as given, else Dask's configuration
    (distributed.Security()); a tls:// or wss:// address without certificates is a ValueError."""
    from distributed.comm.addressing import parse_address
    from distributed.security import Security

    try:
        scheme = parse_address(address)[0]
    except ValueError as exc:
        raise InputError(f"{where}: {_one_line(exc)}; {ALLOWED}") from None
    security = Security() if security is None else security
    if scheme in ("tls", "wss") and security.get_connection_args("client").get("ssl_context") is None:
        raise InputError(
            f"{where}: {scheme}:// needs the cluster's TLS certificates, and none are set: pass "
            "security= (a distributed.Security) from Python, or set distributed.comm.tls.ca-file, "
            ".client.cert and .client.key in Dask's configuration (DASK_DISTRIBUTED__COMM__TLS__CA_FILE "
            "and the like), or use tcp://host:port"
        )
    return security


def _reach(address: str, timeout: float, security, where: str) -> None:
    """ValueError unless a Dask scheduler answers at ``address``: the scheme checked, then a
    plain connection to the host's port within `PROBE_SECONDS`, then Dask's handshake within
    `HANDSHAKE_SECONDS` (and ``timeout``)."""
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    from distributed.comm import connect
    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.comm.inproc import global_manager
    from distributed.comm.registry import backends

    scheme, loc = parse_address(address)
    if scheme not in backends or scheme == "ucx":
        why = (
            "the ucx protocol is no longer part of dask.distributed (it needs distributed-ucxx and a UCX network)"
            if scheme == "ucx"
            else f"unknown address scheme {scheme!r}"
        )
        raise InputError(f"{where}: {why}; {ALLOWED}")
    if scheme == "inproc":
        try:
            listener = global_manager.get_listener_for(loc)
        except ValueError:  # not an inproc address distributed could have made
            listener = None
        if listener is None:
            raise InputError(
                f"{where}: no scheduler of this process listens there (an inproc:// address reaches a "
                f"scheduler started in the same Python process only); {ALLOWED}"
            )
        return
    try:
        host, port = parse_host_port(loc)
    except ValueError as exc:
        raise InputError(f"{where}: {_one_line(exc)}; {ALLOWED}") from None
    probe = min(timeout, PROBE_SECONDS)
    try:
        with socket.create_connection((host, port), timeout=probe) as sock:
            context = security.get_connection_args("client").get("ssl_context")
            if scheme in ("tls", "wss") and context is not None:  # else the server logs a failed handshake
                context.wrap_socket(sock, server_hostname=host).close()
    except ConnectionRefusedError:
        raise InputError(
            f"{where}: cannot reach the Dask scheduler at {address}: nothing listens on port {port} of "
            f"{host} (connection refused); is the scheduler running, and is {port} its port (8786 by default)?"
        ) from None
    except socket.gaierror as exc:
        raise InputError(
            f"{where}: cannot reach the Dask scheduler at {address}: unknown host {host!r} ({exc.strerror})"
        ) from None
    except (TimeoutError, socket.timeout):
        raise InputError(
            f"{where}: cannot reach the Dask scheduler at {address}: {host} did not answer on port {port} "
            f"within {probe:g} s (a host that is down, or a firewall)"
        ) from None
    except OSError as exc:
        raise InputError(
            f"{where}: cannot reach the Dask scheduler at {address}: {exc.strerror or _one_line(exc)}"
        ) from None

    wait = min(timeout, HANDSHAKE_SECONDS)

    async def once():
        comm = await connect(address, timeout=wait, **security.get_connection_args("client"))
        await comm.close()

    try:
        # in a thread of its own: the caller may be inside an event loop (Jupyter)
        with ThreadPoolExecutor(1) as pool:
            pool.submit(lambda: asyncio.run(asyncio.wait_for(once(), wait))).result()
    except Exception as exc:
        raise InputError(
            f"{where}: cannot reach the Dask scheduler at {address}: port {port} accepts connections but "
            f"did not answer as a Dask scheduler within {wait:g} s ({type(exc).__name__}: {_one_line(exc)}); "
            "is it the dashboard's port (8787 by default) rather than the scheduler's (8786)?"
        ) from None


# -- the table of finished runs ----------------------------------------------------------------
#: the lock file beside a run table: held (flock) by the process that writes the table
LOCK_SUFFIX = ".lock"


#: a run table on disk is rewritten at most every max(`WRITE_EVERY_S`, `WRITE_SHARE` x the last
#: write's time) seconds, and always by `RunTable.flush` and `RunTable.close`: writing a table of
#: 35,000 runs takes over a second, and after every chunk it took most of a long design's time
WRITE_EVERY_S = 2.0
WRITE_SHARE = 20.0


class RunTable:
    """Every finished run, one row each, kept in a CSV file rewritten atomically: a reader
    never sees half a file. The file is rewritten after a chunk when the last write is more
    than max(`WRITE_EVERY_S`, `WRITE_SHARE` x its own time) seconds old, so that writing takes
    at most about 5 % of a study's time however long the table grows, and always by `flush`
    and `close` (leaving a ``with`` block; the command line's Ctrl-C and every command's end)
    and when `railride.studies.sweep.run_cases` returns. A process that is killed outright loses
    the runs since the last write, at most that interval; Ctrl-C loses none.

    A table on disk belongs to one process at a time: opening it takes an exclusive lock on the
    file ``.runs.csv.lock`` beside it (the folder is created for it), which names the process
    holding it; a second writer gets a ValueError naming the folder and that process, where it
    would otherwise overwrite the first one's rows. The operating system drops the lock when
    its process ends, however it ends, so the lock of a killed process is simply taken over.
    `close` (or leaving a ``with`` block) releases it. Opening the table also removes what
    killed writes left there (``.runs.csv.*.part``). Rows read back are checked: a damaged
    file is a ValueError naming the file and the line."""

    def __init__(self, path: str | Path | None = None, resume: bool = False):
        self.path = None if path is None else Path(path)
        self._parts: list[pd.DataFrame] = []  # the rows, in the order added; concatenated when read
        self._frame: pd.DataFrame | None = pd.DataFrame()
        self._done: dict[str, dict] = {}
        self._unwritten = False
        self._written_at = -math.inf
        self._write_s = 0.0
        self._lock = None
        if self.path is None:
            return
        self._lock = _FolderLock(self.path)
        try:
            if self.path.exists():
                if not resume:
                    raise InputError(
                        f"{self.path} exists: pass resume to continue that sweep, or choose another output folder"
                    )
                frame = read_run_table(self.path)
                self._parts = [frame]
                self._frame = frame
                self._done = {row["key"]: row for row in frame.to_dict("records")}
        except BaseException:
            self.close()
            raise

    @property
    def frame(self) -> pd.DataFrame:
        """Every run so far, one row each, in the order they finished."""
        if self._frame is None:
            self._frame = pd.concat(self._parts, ignore_index=True) if self._parts else pd.DataFrame()
            self._parts = [self._frame]
        return self._frame

    def flush(self) -> None:
        """Write every run so far to the file now (nothing for a table in memory)."""
        if self.path is None or not self._unwritten:
            return
        frame = self.frame
        t0 = time.perf_counter()
        atomic_write(self.path, lambda p: frame.to_csv(p, index=False))
        self._write_s = time.perf_counter() - t0
        self._written_at = time.perf_counter()
        self._unwritten = False

    def close(self) -> None:
        """Write what is left and release the table's lock (nothing for a table in memory); the
        table stays readable."""
        try:
            if self._lock is not None:
                self.flush()
        finally:
            if self._lock is not None:
                self._lock.release()
                self._lock = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def done(self) -> dict[str, dict]:
        """The finished runs by key (a new dict: the caller may add to it)."""
        return dict(self._done)

    def add(self, rows: list[dict]) -> None:
        if not rows:
            return
        self._parts.append(pd.DataFrame(rows))
        self._frame = None
        self._done.update((row["key"], row) for row in rows)
        self._unwritten = True
        if self.path is not None and time.perf_counter() - self._written_at >= max(
            WRITE_EVERY_S, WRITE_SHARE * self._write_s
        ):
            self.flush()


def read_run_table(path: Path) -> pd.DataFrame:
    """The rows of the run table ``path``, checked: every row has a key (16 hex digits) and,
    unless it records the time its run diverged, finite numbers in its metric columns. A
    ValueError names the file, the line and what is wrong. The ``vehicle`` column (the name of
    the vehicle a run ran, `railride.studies.sweep.run_cases`) is text; a table written before
    it has none, and reads as it did."""
    from railride.analysis.metrics import RESPONSES, STATISTICS

    try:
        # keys are hex digests: an all-digit one must stay text to be recognised; so must a
        # vehicle named by a file whose name is a number
        frame = pd.read_csv(path, dtype={"key": str, "vehicle": str})
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot read the run table {path}: {' '.join(str(exc).split())}") from None
    if "key" not in frame:
        raise InputError(f"run table {path}: no 'key' column; not a railride run table")
    metrics = [c for c in (f"{r}_{s}" for r in RESPONSES for s in STATISTICS) if c in frame]
    values = frame[metrics].apply(pd.to_numeric, errors="coerce")
    diverged = pd.to_numeric(frame["diverged_at_s"], errors="coerce") if "diverged_at_s" in frame else None
    keys = frame["key"].astype(str).str.fullmatch("[0-9a-f]{16}") & frame["key"].notna()
    finite = np.isfinite(values.to_numpy(dtype=float)).all(axis=1)
    ran = ~np.isfinite(diverged.to_numpy(dtype=float)) if diverged is not None else np.ones(len(frame), bool)
    bad = np.flatnonzero(~keys.to_numpy() | (ran & ~finite))
    if bad.size:
        i = int(bad[0])
        if not keys.iloc[i]:
            problem = f"key = {frame['key'].iloc[i]!r} is not 16 hex digits"
        else:
            column = next(c for c in metrics if not np.isfinite(values[c].iloc[i]))
            problem = f"{column} = {frame[column].iloc[i]!r} is not a finite number (and the run did not diverge)"
        raise InputError(
            f"run table {path}, line {i + 2} (run {i + 1}): {problem}; the file is damaged: "
            "delete that line to run it again, or start afresh in another folder"
        )
    frame[metrics] = values
    return frame


class _FolderLock:
    """An exclusive lock on ``.NAME.lock`` beside ``path`` (flock: held while the file is open,
    dropped by the system when the process ends). The file names its holder for the error."""

    def __init__(self, path: Path):
        import fcntl

        self.fd: int | None = None
        self.path = path.parent / f".{path.name}{LOCK_SUFFIX}"
        folder = path.parent
        self.created = not folder.exists()
        folder.mkdir(parents=True, exist_ok=True)
        while True:
            fd = self._open()
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 200).decode("utf-8", "replace").strip() or "another process"
                os.close(fd)
                raise InputError(
                    f"output folder {folder} is in use by {holder} (lock {self.path}): two runs writing one "
                    "run table would lose rows; wait for it to finish, or choose another folder"
                ) from None
            # the file may have been removed by its holder between our open and flock: retry on
            # the new one, or two processes would hold locks on different files
            try:
                same = os.path.samestat(os.fstat(fd), os.lstat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        self.fd = fd
        os.ftruncate(fd, 0)
        os.write(fd, f"railride process {os.getpid()} on {socket.gethostname()}, since {_now()}\n".encode())
        for part in folder.glob(f".{path.name}.*.part"):  # a killed atomic write's leftovers
            part.unlink(missing_ok=True)

    def _open(self) -> int:
        """The lock file, opened without following a link (O_NOFOLLOW) and refused unless it is a
        regular file: a link planted there would have the run truncate the file it points to."""
        import errno
        import stat

        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
        except OSError as exc:
            if exc.errno == errno.EISDIR:
                raise InputError(f"lock {self.path} is not a regular file: refused; remove it") from None
            if exc.errno != errno.ELOOP:
                raise
            raise InputError(
                f"lock {self.path} is a symbolic link: refused, since writing the lock would write where it "
                "points; remove it"
            ) from None
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise InputError(f"lock {self.path} is not a regular file: refused; remove it")
        return fd

    def release(self) -> None:
        if self.fd is None:
            return
        self.path.unlink(missing_ok=True)  # while still held: no one else is between
        os.close(self.fd)
        self.fd = None
        if self.created:  # a folder made only for the lock, with nothing written, goes again
            try:
                self.path.parent.rmdir()
            except OSError:
                pass

    def __del__(self):
        self.release()


def _now() -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S")
