"""Every law's tuning in one batch a round (`railride.studies.tuning.tune`).

A law's search (the paper's sensitivity study, or differential evolution:
`railride.studies.evolution`) is a generator: it yields the gain sets it wants scored and
receives their objectives. `lockstep` steps the searches of every law together, so that each
round's gain sets of every law, over every case of the tuning set, are one call of
`railride.studies.sweep.run_cases`: one pass over the executor's workers, a Dask cluster's
included.

Each search sees exactly what it would see alone, so its path, and the gains it ends with, do not
depend on the other laws. So that the runs do not either, to the last bit, `OwnChunks` runs each
law's cases in the chunks that law's own call of `run_cases` would make: a chunk is one compiled
batch, and the compiled stepper's results depend on a run's batch-mates in the last bits (the
lane stepper for batches of `railride.engine.lanes.LANES` runs or more, the scalar one below).
The chunks of all laws go in the order of the tables they read, so that the laws' chunks on
the same tracks and speeds run one after another and find those tables kept
(`railride.run.inputs`): a round builds each of its tables about once, not once a law.

On the GPU a run is one thread, whose arithmetic has no batch-mates: there the round's runs of
every law are one batch (as many as fit `railride.studies.sweep.GPU_CHUNK`), which builds and
sends each table once.
"""

from __future__ import annotations


def lockstep(searches: dict, score) -> dict:
    """Step the ``searches`` (by law: generators that yield lists of gain sets and receive their
    objectives) together: each round, one request of every live search goes to ``score`` (a
    dict of them by law, which it scores in one batch of runs and answers by law), and each
    answer goes back to its search. Returns what each search returned, in the order given.
    Searches left unfinished (an error, Ctrl-C) are closed."""
    asked, done = {}, {}
    try:
        for name, gen in searches.items():
            try:
                asked[name] = next(gen)
            except StopIteration as stop:
                done[name] = stop.value
        while asked:
            scores = score(asked)
            for name in list(asked):
                try:
                    asked[name] = searches[name].send(scores[name])
                except StopIteration as stop:
                    done[name] = stop.value
                    del asked[name]
    finally:
        for gen in searches.values():
            gen.close()
    return {name: done[name] for name in searches}


class OwnChunks:
    """The executor of one `lockstep` round: ``executor`` (default a `LocalExecutor`) runs the
    chunks of every law in one pass, each law's as its own `run_cases` call of ``parts`` (its
    cases, in the order asked; one list per law) would chunk them."""

    def __init__(self, executor, parts):
        from railride.studies.executors import LocalExecutor
        from railride.studies.sweep import CHUNK

        self.executor = LocalExecutor() if executor is None else executor
        self.parts = parts
        self.chunk = CHUNK  # the runs of a chunk: `run_cases` sets it (larger on a GPU)
        self.on_gpu = False  # whether the chunks step on the GPU: `run_cases` sets it

    def map(self, fn, chunks):
        """``executor.map`` of the chunks of each law's cases among those in ``chunks`` (the
        cases `run_cases` found missing from its table), in the order of the tables they read;
        on the GPU, every law's together."""
        from railride.studies.sweep import _chunks, table_order

        pending = {c.key for chunk in chunks for c in chunk}
        seen: set = set()
        mine = [[c for c in part if c.key in pending and not (c.key in seen or seen.add(c.key))] for part in self.parts]
        if self.on_gpu:  # one thread a run: no batch-mates in its arithmetic
            return self.executor.map(fn, _chunks([c for part in mine for c in part], self.chunk))
        own = [chunk for part in mine for chunk in _chunks(part, self.chunk)]
        near = table_order([c for chunk in own for c in chunk])
        own.sort(key=lambda chunk: near(chunk[0]))  # stable: a tie keeps the laws' order
        return self.executor.map(fn, own)

    def bounded(self, chunk_bytes: float) -> "OwnChunks":
        """The same, over ``executor.bounded(chunk_bytes)`` where it has that (`LocalExecutor`)."""
        if not hasattr(self.executor, "bounded"):
            return self
        return OwnChunks(self.executor.bounded(chunk_bytes), self.parts)

    def close(self) -> None:
        """Nothing: the executor is the caller's, and closed by it."""
