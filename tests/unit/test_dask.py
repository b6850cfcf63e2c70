"""The Dask executor against a real cluster on loopback: a scheduler and two workers started as
processes of this Python (one process and one thread each, every port on 127.0.0.1), sweeps
equal to the local executor's to the last bit, a resumed run table, a worker killed mid-sweep,
and schedulers that cannot be reached."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numba
import pandas as pd
import pytest

pytest.importorskip("distributed")
from distributed import Client  # noqa: E402

from railride.secondary.control import GainSet  # noqa: E402
from railride.analysis.metrics import RESPONSES, STATISTICS  # noqa: E402
from railride.studies.executors import DaskExecutor, LocalExecutor, RunTable  # noqa: E402
from railride.studies.sweep import Case, SweepResult, grid, run_cases, run_sweep  # noqa: E402

#: seconds for the scheduler file and for the workers to come up (imports on a slow machine)
STARTUP = 60.0
#: seconds a sweep may take before the test gives up instead of hanging
SWEEP = 60.0
METRICS = [f"{r}_{s}" for r in RESPONSES for s in STATISTICS]
#: the base gains of every run here, read once: the shipped file may change while the tests run
BASE = GainSet.default()


def _settings(case):
    return json.loads(json.dumps(case.to_dict(), default=str))


def _cases(speeds=(30.0, 40.0, 50.0, 55.56), duration=1.0):
    return [
        Case(scenario_options={"duration": duration, "speed": v}, suspension=s)
        for s in ("passive", "pid")
        for v in speeds
    ]


class Cluster:
    """A scheduler and workers as subprocesses in their own process groups."""

    def __init__(self, folder):
        self.folder = folder
        self.scheduler_file = str(folder / "scheduler.json")
        self.procs: dict[str, subprocess.Popen] = {}
        self.address = None
        # NUMBA_NUM_THREADS left at the machine's cores: the executor shares them out
        self.env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}
        self.env["PYTHONUNBUFFERED"] = "1"

    def _spawn(self, name, args):
        log = open(self.folder / f"{name}.log", "wb")
        try:
            self.procs[name] = subprocess.Popen(
                [sys.executable, "-m", *args],
                stdout=log,
                stderr=subprocess.STDOUT,
                env=self.env,
                cwd=self.folder,
                start_new_session=True,
            )
        finally:
            log.close()

    def log(self, name, lines=30):
        text = (self.folder / f"{name}.log").read_text(errors="replace").splitlines()
        return "\n".join(text[-lines:])

    def start_scheduler(self):
        # --idle-timeout: should this test process die without its teardown, the scheduler
        # quits on its own, and the workers after it (--death-timeout)
        self._spawn(
            "scheduler",
            [
                "distributed.cli.dask_scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--dashboard-address",
                "127.0.0.1:0",
                "--scheduler-file",
                self.scheduler_file,
                "--idle-timeout",
                "300s",
            ],
        )
        deadline = time.monotonic() + STARTUP
        while self.address is None:
            self._check_alive("scheduler")
            with contextlib.suppress(OSError, ValueError, KeyError):
                with open(self.scheduler_file) as f:
                    self.address = json.load(f)["address"]
            if time.monotonic() > deadline:
                raise RuntimeError(f"no scheduler file after {STARTUP} s:\n{self.log('scheduler')}")
            time.sleep(0.1)

    def start_worker(self, name):
        self._spawn(
            name,
            [
                "distributed.cli.dask_worker",
                "--scheduler-file",
                self.scheduler_file,
                "--host",
                "127.0.0.1",
                "--dashboard-address",
                "127.0.0.1:0",
                "--nworkers",
                "1",
                "--nthreads",
                "1",
                "--no-nanny",
                "--name",
                name,
                "--local-directory",
                str(self.folder / name),
                "--death-timeout",
                "60",
            ],
        )

    def wait_for_workers(self, names):
        """{name: address} once every worker in ``names`` is connected."""
        deadline = time.monotonic() + STARTUP
        with Client(self.address, timeout=STARTUP, set_as_default=False) as client:
            while True:
                for name in ["scheduler", *names]:
                    self._check_alive(name)
                workers = client.scheduler_info()["workers"]
                found = {w["name"]: addr for addr, w in workers.items()}
                if all(n in found for n in names):
                    return {n: found[n] for n in names}
                if time.monotonic() > deadline:
                    logs = "\n".join(f"--- {n}\n{self.log(n)}" for n in names)
                    raise RuntimeError(
                        f"workers {names} not all connected after {STARTUP} s (connected: {sorted(found)}):\n{logs}"
                    )
                time.sleep(0.2)

    def _check_alive(self, name):
        proc = self.procs[name]
        if proc.poll() is not None:
            raise RuntimeError(f"{name} exited with {proc.returncode}:\n{self.log(name)}")

    def kill(self, name, sig=signal.SIGKILL):
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.procs[name].pid, sig)

    def stop(self):
        """The workers, then the scheduler (a worker stopped together with its scheduler can
        hang in its shutdown): SIGTERM, and SIGKILL to the whole group of whatever is left."""
        workers = [n for n in self.procs if n != "scheduler"]
        for group in (workers, ["scheduler"] if "scheduler" in self.procs else []):
            for name in group:
                self.kill(name, signal.SIGTERM)
            for name in group:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    self.procs[name].wait(timeout=10)
                self.kill(name, signal.SIGKILL)
                self.procs[name].wait(timeout=10)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    c = Cluster(tmp_path_factory.mktemp("dask"))
    try:
        c.start_scheduler()
        c.start_worker("w1")
        c.start_worker("w2")
        c.workers = c.wait_for_workers(["w1", "w2"])
        yield c
    finally:
        c.stop()


@pytest.fixture(scope="module")
def local():
    """The reference: the same sweep on the local executor, in this process."""
    return run_cases(_cases(), executor=LocalExecutor(), chunk=2, base_gains=BASE)


def _run(cases, executor, **kwargs):
    """run_cases in a thread that may take at most SWEEP seconds (a hung cluster fails the test
    instead of hanging the suite)."""
    kwargs.setdefault("base_gains", BASE)
    return _within(lambda: run_cases(cases, executor=executor, **kwargs))


def _within(call):
    """``call()`` in a thread that may take at most SWEEP seconds."""
    out = {}

    def target():
        try:
            out["frame"] = call()
        except BaseException as exc:  # re-raised below
            out["error"] = exc

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(SWEEP)
    if thread.is_alive():
        pytest.fail(f"the sweep did not finish within {SWEEP} s")
    if "error" in out:
        raise out["error"]
    return out["frame"]


class Counting:
    """An executor that counts the chunks and cases handed to the one it wraps."""

    def __init__(self, inner):
        self.inner, self.name, self.chunks, self.cases = inner, inner.name, 0, 0

    def map(self, fn, chunks):
        chunks = list(chunks)
        self.chunks += len(chunks)
        self.cases += sum(len(c) for c in chunks)
        return self.inner.map(fn, chunks)

    def close(self):
        self.inner.close()


def test_the_cluster_listens_on_loopback_only(cluster):
    psutil = pytest.importorskip("psutil")
    assert cluster.procs  # the loop below checks something
    for name, proc in cluster.procs.items():
        p = psutil.Process(proc.pid)
        conns = p.net_connections("inet") if hasattr(p, "net_connections") else p.connections("inet")
        listening = [c.laddr for c in conns if c.status == psutil.CONN_LISTEN]
        assert listening, name
        assert all(a.ip == "127.0.0.1" for a in listening), (name, listening)


def test_each_chunk_runs_on_its_share_of_the_cores(cluster):
    def probe(chunk):
        import numba
        from distributed import get_worker

        return get_worker().address, numba.get_num_threads()

    executor = DaskExecutor(scheduler_file=cluster.scheduler_file, timeout=10)
    try:
        out = dict(executor.map(probe, [[i] for i in range(6)]))
    finally:
        executor.close()
    assert sorted(out) == list(range(6))
    # two workers of one thread each on this machine: each chunk gets half its cores
    cores = numba.config.NUMBA_DEFAULT_NUM_THREADS  # the workers' (NUMBA_NUM_THREADS unset)
    assert {threads for _, threads in out.values()} == {max(1, cores // 2)}
    assert {address for address, _ in out.values()} <= set(cluster.workers.values())


def test_a_sweep_by_scheduler_file_equals_the_local_one(cluster, local):
    executor = DaskExecutor(scheduler_file=cluster.scheduler_file, timeout=10)
    try:
        # chunks of 2: four tasks over the two workers
        dask = _run(_cases(), executor, chunk=2)
    finally:
        executor.close()
    # rows in the cases' order, whatever order the chunks finished in
    assert [json.loads(c) for c in dask["case"]] == [_settings(c) for c in _cases()]
    pd.testing.assert_frame_equal(dask, local, check_exact=True)


def test_a_sweep_by_address_equals_the_local_one(cluster, local):
    with open(cluster.scheduler_file) as f:
        address = json.load(f)["address"]
    assert address.startswith("tcp://127.0.0.1:")
    executor = DaskExecutor(address=address, timeout=10)
    try:
        # one case a chunk this time: the rows come back in the cases' order all the same
        dask = _run(_cases(), executor, chunk=1)
    finally:
        executor.close()
    pd.testing.assert_frame_equal(dask, local, check_exact=True)


def test_the_sweep_study_on_the_cluster_equals_the_local_one(cluster, local):
    g = grid(["passive", "pid"], speed=[30.0, 40.0, 50.0, 55.56], duration=1.0, base_gains=BASE)
    assert [c.to_dict() for c in g.cases] == [c.to_dict() for c in _cases()]
    executor = DaskExecutor(scheduler_file=cluster.scheduler_file, timeout=10)
    try:
        result = _within(lambda: run_sweep(g, executor=executor, comfort=False))
    finally:
        executor.close()
    pd.testing.assert_frame_equal(result.to_pandas(), SweepResult(g, local).to_pandas(), check_exact=True)


def test_a_resumed_run_table_runs_only_what_is_missing(cluster, local, tmp_path):
    path = tmp_path / "runs.csv"
    cases = _cases()
    first = Counting(DaskExecutor(scheduler_file=cluster.scheduler_file, timeout=10))
    try:
        _run(cases[::2], first, table=RunTable(path), chunk=2)
    finally:
        first.close()
    assert first.cases == 4
    assert len(pd.read_csv(path)) == 4

    # resumed with every case: only the other half runs
    second = Counting(DaskExecutor(scheduler_file=cluster.scheduler_file, timeout=10))
    try:
        frame = _run(cases, second, table=RunTable(path, resume=True), chunk=2)
    finally:
        second.close()
    assert (second.chunks, second.cases) == (2, 4)
    assert list(frame["key"]) == list(local["key"])
    assert len(pd.read_csv(path)) == 8

    # resumed again: nothing left to run, every row from the table (as written, through CSV)
    third = Counting(DaskExecutor(scheduler_file=cluster.scheduler_file, timeout=10))
    try:
        frame = _run(cases, third, table=RunTable(path, resume=True), chunk=2)
    finally:
        third.close()
    assert (third.chunks, third.cases) == (0, 0)
    assert list(frame["key"]) == list(local["key"])
    assert (frame[METRICS].to_numpy() == local[METRICS].to_numpy()).all()


def test_a_worker_killed_mid_sweep_changes_nothing(cluster):
    cases = _cases(speeds=(30.0, 35.0, 40.0, 45.0, 50.0, 55.56), duration=2.0)
    reference = run_cases(cases, executor=LocalExecutor(), chunk=1, base_gains=BASE)

    cluster.start_worker("w3")
    w3 = cluster.wait_for_workers(["w3"])["w3"]
    watcher = Client(cluster.address, timeout=10, set_as_default=False)
    killed = {}

    def kill_w3_once_it_holds_a_chunk():
        # w3 is fresh: its first chunk loads the compiled kernels first, so it is killed while
        # that chunk runs, with the sweep under way
        deadline = time.monotonic() + SWEEP
        while time.monotonic() < deadline:
            held = watcher.processing(workers=[w3]).get(w3, [])
            if any(str(k).startswith("railride-chunk-") for k in held):
                cluster.kill("w3")
                killed["chunks"] = list(held)
                return
            time.sleep(0.01)

    thread = threading.Thread(target=kill_w3_once_it_holds_a_chunk, daemon=True)
    executor = DaskExecutor(scheduler_file=cluster.scheduler_file, timeout=10)
    try:
        thread.start()
        dask = _run(cases, executor, chunk=1)
        thread.join(SWEEP)
        # the scheduler dropped w3 and ran its chunk elsewhere
        deadline = time.monotonic() + SWEEP  # a guard against hanging, not a measure of speed
        while w3 in watcher.scheduler_info()["workers"]:
            if time.monotonic() > deadline:
                pytest.fail(f"the scheduler still lists the killed worker after {SWEEP:g} s")
            time.sleep(0.1)
    finally:
        executor.close()
        watcher.close()
        cluster.kill("w3")
    assert killed, "w3 never received a chunk, so it was not killed mid-sweep"
    assert cluster.procs["w3"].wait(timeout=10) == -signal.SIGKILL
    pd.testing.assert_frame_equal(dask, reference, check_exact=True)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def clients(monkeypatch):
    """The distributed.Client objects `DaskExecutor` tries to make, none of them made: a Client
    waits up to its timeout for a scheduler (and a half-made one for 20 s more as it is
    collected), so a refusal that comes before any Client is a quick one on any machine."""
    import distributed

    tried = []

    def client(*args, **kwargs):
        tried.append(args)
        raise AssertionError("DaskExecutor made a Client before refusing the address")

    monkeypatch.setattr(distributed, "Client", client)
    return tried


def test_an_unreachable_scheduler_is_a_quick_value_error(clients):
    address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    with pytest.raises(ValueError, match=f"cannot reach the Dask scheduler at {address}"):
        DaskExecutor(address=address, timeout=2)
    assert clients == []  # refused by its own probe, before a Client


def test_a_port_that_does_not_speak_dask_is_a_quick_value_error(clients):
    # accepts connections and never answers, like a web server: distributed's Client alone
    # would wait for its handshake forever
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
        with pytest.raises(ValueError, match=f"cannot reach the Dask scheduler at {address}"):
            DaskExecutor(address=address, timeout=2)
    assert clients == []  # refused by its own handshake check, before a Client


def test_a_missing_or_broken_scheduler_file_is_a_quick_value_error(tmp_path, clients):
    # distributed's Client would wait for a missing file forever: the executor waits its timeout
    with pytest.raises(ValueError, match="no such file after 1 s"):
        DaskExecutor(scheduler_file=str(tmp_path / "nothing.json"), timeout=1)
    broken = tmp_path / "broken.json"
    broken.write_text("{}")
    with pytest.raises(ValueError, match="not a Dask scheduler file .* after 1 s"):
        DaskExecutor(scheduler_file=str(broken), timeout=1)
    assert clients == []


def test_an_unknown_scheme_or_both_targets_are_value_errors(tmp_path):
    with pytest.raises(ValueError, match="unknown address scheme"):
        DaskExecutor(address="udp://127.0.0.1:1", timeout=1)
    with pytest.raises(ValueError, match="scheduler address .* or a scheduler file"):
        DaskExecutor(address="tcp://127.0.0.1:1", scheduler_file=str(tmp_path / "s.json"))


def _double(chunk):
    return [2 * c for c in chunk]


@pytest.mark.parametrize("protocol", ["inproc", "tcp://", "ws://", "tls://", "wss://"])
def test_every_scheme_the_errors_allow_runs_chunks(protocol):
    from distributed import LocalCluster
    from distributed.security import Security

    pytest.importorskip("cryptography")  # Security.temporary's certificates
    security = Security.temporary() if protocol in ("tls://", "wss://") else None
    options = dict(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None)
    if protocol != "inproc":
        options.update(protocol=protocol, host="127.0.0.1")
    with LocalCluster(**options, **({"security": security} if security else {})) as cluster:
        executor = DaskExecutor(address=cluster.scheduler_address, security=security, timeout=10)
        try:
            assert sorted(executor.map(_double, [[1], [2, 3]])) == [(0, [2]), (1, [4, 6])]
        finally:
            executor.close()


@pytest.mark.parametrize(
    "address,fragment",
    [
        ("tls://127.0.0.1:{port}", "needs the cluster's TLS certificates"),
        ("wss://127.0.0.1:{port}", "needs the cluster's TLS certificates"),
        ("ucx://127.0.0.1:{port}", "distributed-ucxx"),
        ("inproc://127.0.0.1/1/1", "no scheduler of this process listens there"),
        ("inproc://nonsense", "no scheduler of this process listens there"),
        ("udp://127.0.0.1:{port}", "unknown address scheme"),
        ("tcp://127.0.0.1", "missing port"),
        ("tcp://127.0.0.1:{port}", "nothing listens on port {port} of 127.0.0.1 (connection refused)"),
        ("127.0.0.1:{port}", "connection refused"),
        ("tcp://nowhere.invalid:8786", "unknown host 'nowhere.invalid'"),
    ],
)
def test_an_address_that_cannot_work_is_refused_at_once_naming_it(address, fragment, clients):
    port = _free_port()  # nothing listens there
    address, fragment = address.format(port=port), fragment.format(port=port)
    with pytest.raises(ValueError) as info:
        DaskExecutor(address=address, timeout=30)
    assert clients == []  # refused by the checks, which do not wait for the timeout as a Client would
    message = str(info.value)
    assert message.startswith(f"address = {address!r}: ") and fragment in message, message
