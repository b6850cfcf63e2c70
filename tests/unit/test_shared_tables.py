"""What runs share and what a study keeps: the random-track realisations and the rail input tables
are kept within a budget of bytes, by their settings (a kept table does not keep its track); a
study's runs are taken scenario by scenario, so the runs on one scenario sit in neighbouring
chunks; and a sweep keeps no run's histories once its chunk is done."""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pytest

import railride as rr
from railride.run import simulation
from railride.model import track
from railride._cache import BytesLRU
from railride.run.ride import RideResult
from railride.studies.sweep import Case, _chunks, grid, run_cases


@pytest.fixture
def fresh_stores():
    """Empty tracks and tables before and after (a test's small budgets do not leak out)."""
    stores = (track._TRACKS, simulation._INPUT_TABLES, simulation._FORCING_TABLES)
    budgets = [s.budget for s in stores]
    for s in stores:
        s.clear()
    yield stores
    for s, b in zip(stores, budgets):
        s.budget = b
        s.clear()


def test_a_store_holds_at_most_its_budget_and_drops_the_least_recently_used():
    built = []

    def build(n):
        def make():
            built.append(n)
            return np.zeros(n, dtype=np.uint8)

        return make

    store = BytesLRU("test", 1000, lambda a: a.nbytes)
    rng = np.random.default_rng(3)
    for i in range(300):
        key = int(rng.integers(0, 40))
        value = store.get(key, build(10 * key + 5))
        assert value.nbytes == 10 * key + 5  # the value of that key, kept or built
        assert store.nbytes <= 1000
    store.clear()
    a = store.get("a", build(400))
    store.get("b", build(400))
    assert store.get("a", build(400)) is a  # kept: the same array, not built again
    store.get("c", build(400))  # 1200 bytes: the least recently used ("b") goes
    n = len(built)
    assert store.get("a", build(400)) is a and len(built) == n
    store.get("b", build(400))
    assert len(built) == n + 1
    # larger than the whole budget, or no plain key: built each time, never kept
    store.get("big", build(2000))
    store.get("big", build(2000))
    store.get(["not", "hashable"], build(10))
    assert built[-3:] == [2000, 2000, 10] and store.nbytes <= 1000


def test_input_tables_stay_within_their_budget(fresh_stores):
    simulation._INPUT_TABLES.budget = 400_000  # about two tables of 1 s at these speeds
    speeds = [30.0, 35.0, 40.0, 45.0, 50.0, 55.0]
    first = [rr.simulate(rr.scenario("fra4", seed=1, speed=v, duration=1.0)).metrics() for v in speeds]
    assert 0 < len(simulation._INPUT_TABLES) < len(speeds)
    assert simulation._INPUT_TABLES.nbytes <= 400_000
    again = rr.simulate(rr.scenario("fra4", seed=1, speed=30.0, duration=1.0)).metrics()  # built again
    np.testing.assert_array_equal(again.values, first[0].values)


def test_a_kept_table_is_found_by_settings_and_does_not_keep_its_track(fresh_stores):
    sc = rr.scenario("fra4", seed=4242, speed=40.0, duration=1.0)
    realisation = weakref.ref(sc.track)
    rr.simulate(sc)
    kept = len(simulation._INPUT_TABLES)
    assert kept == 1
    del sc
    track._TRACKS.clear()
    gc.collect()
    assert realisation() is None  # only the table is kept, not the realisation it came from
    hits = simulation._INPUT_TABLES.hits
    rr.simulate(rr.scenario("fra4", seed=4242, speed=40.0, duration=1.0))  # a new realisation, same settings
    assert simulation._INPUT_TABLES.hits == hits + 1 and len(simulation._INPUT_TABLES) == kept


def test_the_grid_checks_build_each_realisation_once(fresh_stores):
    track._TRACKS.budget = 8 << 20  # one realisation of the default band
    misses = track._TRACKS.misses
    grid(["passive"], scenario="fra4", speed=[30.0, 40.0, 50.0], track_seed=[0, 1, 2, 3], duration=1.0)
    assert track._TRACKS.misses - misses == 4  # in the grid's order (speed first), 12


def test_the_runs_of_a_scenario_sit_in_neighbouring_chunks():
    g = grid(
        ["passive", "pid", "sas-attitude", "sas-attitude-ride"],
        scenario="fra4",
        speed=[30.0 + 5.0 * i for i in range(8)],
        track_seed=list(range(16)),
        duration=10.0,
    )
    chunks = _chunks(list(g.cases), 32)
    assert sorted(id(c) for part in chunks for c in part) == sorted(id(c) for c in g.cases)
    where: dict[tuple, set] = {}
    for k, part in enumerate(chunks):
        assert 0 < len(part) <= 32 and len({c.group for c in part}) == 1  # one compiled batch
        scenarios = {c.scenario_options for c in part}
        if part[0].suspension != "passive":  # the three controllers on each scenario together
            assert len(scenarios) <= 12
        for s in scenarios:
            where.setdefault(s, set()).add(k)
    # passive and the controllers on a scenario run within three chunks of each other (in the
    # grid's order they were 12 chunks apart, and no store of tables bridged that)
    assert max(max(k) - min(k) for k in where.values()) <= 2


def test_a_sweep_keeps_no_histories(fresh_stores):
    gc.collect()
    before = sum(isinstance(o, RideResult) for o in gc.get_objects())
    cases = [
        Case("fra4", {"seed": s, "speed": 40.0, "duration": 1.0}, suspension=x)
        for s in (0, 1)
        for x in ("passive", "pid")
    ]
    frame = run_cases(cases, chunk=2, comfort=True)
    gc.collect()
    assert len(frame) == 4 and frame["centre_N_MV_z"].notna().all()
    assert sum(isinstance(o, RideResult) for o in gc.get_objects()) <= before


def test_a_batch_builds_its_forcing_tables_in_pieces_over_threads_with_the_rows_of_one_call(fresh_stores, monkeypatch):
    # a batch's forcing tables are built in place, in pieces of rows on numba's threads: each
    # node is its own sum, so the pieces must give what one call over a whole table gives
    import numba

    from railride.engine.tables import forcing_nodes
    from railride.model.params import VehicleParams
    from railride.run import inputs

    scs = [track.scenario("fra4", seed=s, speed=v, duration=1.0) for s in (1, 2) for v in (30.0, 60.0)]
    pars = [VehicleParams.preset("paper"), VehicleParams.preset("paper").loaded(1.3)]
    plan = simulation.check(
        [sc for sc in scs for _ in pars], [p for _ in scs for p in pars], rr.Suspension.named("skyhook")
    )
    monkeypatch.setattr(inputs, "_FORCING_PIECE_ROWS", 200)  # tables of 600-1,300 nodes: 4-7 pieces
    threads = []
    real = inputs._fill_forcing

    def counted(work):
        threads.append(numba.get_num_threads())
        real(work)

    monkeypatch.setattr(inputs, "_fill_forcing", counted)
    tables = simulation.inputs(plan)
    assert threads  # the batch's tables went through the pieces
    for i, (sc, p) in enumerate(zip(plan.scenarios, plan.param_sets)):
        n = int(tables.n_nodes[i])
        utab = tables.utab[tables.u_off[i] : tables.u_off[i] + n]
        arrays = inputs._system_arrays(inputs._vehicle(p))
        whole = np.empty((n, tables.ftab.shape[1]))
        ro = utab.copy()
        ro.flags.writeable = False
        forcing_nodes(ro, arrays["Bw"], arrays["Bwd"], whole)
        assert n > 400 and np.array_equal(tables.ftab[tables.f_off[i] : tables.f_off[i] + n], whole), i


def test_a_batch_keeps_its_forcing_tables_only_where_they_fit_the_store(fresh_stores):
    # a tuning round's tables (300 MB) would push each other out of the store (64 MiB): a batch
    # whose tables do not fit keeps none of them; one that fits keeps each, and a later batch
    # copies them in, the same to the bit
    scs = [track.scenario("fra4", seed=s, speed=45.0, duration=1.0) for s in (1, 2, 3)]
    plan = simulation.check(scs, suspension=rr.Suspension.named("skyhook"))
    forcing = simulation._FORCING_TABLES
    forcing.budget = 1000  # smaller than the batch's tables
    hits, misses = forcing.hits, forcing.misses
    first = simulation.inputs(plan)
    assert len(forcing) == 0 and forcing.misses - misses == 3
    forcing.budget = 64 << 20
    second = simulation.inputs(plan)
    assert len(forcing) == 3 and forcing.misses - misses == 6
    third = simulation.inputs(plan)
    assert forcing.hits - hits == 3 and len(forcing) == 3
    assert np.array_equal(first.ftab, second.ftab) and np.array_equal(second.ftab, third.ftab)
    assert np.array_equal(first.f_off, third.f_off) and first.ftab.shape[0] == first.utab.shape[0]


def test_vehicles_that_differ_where_no_wheelset_reaches_share_a_forcing_table(fresh_stores):
    # a payload changes the carbody, which the rail inputs reach only through the bogies: the
    # loaded car's forcing table is the empty car's, built once; a stiffer primary is its own
    from railride.model.params import VehicleParams
    from railride.run import inputs

    sc = track.scenario("fra4", seed=1, speed=45.0, duration=1.0)
    empty = VehicleParams.preset("paper")
    stiff = empty.replace(k_pz=2.0 * empty.k_pz)
    pars = [empty, empty.loaded(1.3), stiff]
    plan = simulation.check([sc] * 3, pars, rr.Suspension.named("skyhook"))
    tables = simulation.inputs(plan)
    n = int(tables.n_nodes[0])
    assert tables.f_off[0] == tables.f_off[1] != tables.f_off[2] and tables.ftab.shape[0] == 2 * n
    utab = tables.utab[:n]
    for i, p in enumerate(pars):  # each vehicle's rows are its own matrices times the rails
        arrays = inputs._system_arrays(inputs._vehicle(p))
        own = inputs._forcing_table(utab, arrays["Bw"], arrays["Bwd"])
        assert np.array_equal(tables.ftab[tables.f_off[i] : tables.f_off[i] + n], own), i
