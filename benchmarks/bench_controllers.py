"""Cost of each control law in the closed loop, and of a league table.

Run:  python benchmarks/bench_controllers.py [--repeat N] [--threads N] [--no-league] [--vehicles]
Prints a Markdown table for docs/performance.md: per law, one 10 s run on `paper-sine` with four
`railway` MR dampers (dt = 1e-4 s, 100 000 steps), its time per step and the ratio to SAS
(attitude+ride); then a league table of five controllers on three scenarios at two speeds, warm.
Wall-clock minima over the repeats, and the minimum of the process's CPU time, which other jobs on
a shared machine disturb less (with one thread it is the run's own time on its core); no test
asserts timings. ``--threads 1`` measures one core, and adds the compiled stepper's own CPU
time per step (the thread's time around the kernel call, without the input table and metrics).
``--vehicles`` measures instead what the vehicle's elements cost per step: the paper's rigid
vehicle, on 2 MN/m bump stops at 80 mm (off them on this track), and with a 24 m carbody bending
at 10 Hz, each under SAS (attitude+ride) and skyhook, one run and a batch of 16 (the lane
stepper), with the ratio to the rigid vehicle.
"""

from __future__ import annotations

from _timing import min_time  # benchmarks/_timing.py: run as a script, this folder is on the path

import argparse
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", type=int, default=0, help="numba threads (default: numba's)")
    ap.add_argument("--no-league", action="store_true", help="leave out the league table")
    ap.add_argument("--vehicles", action="store_true", help="the cost of bump stops and a bending carbody")
    args = ap.parse_args()
    if args.vehicles:
        return vehicles(args)

    import numba

    if args.threads > 0:
        numba.set_num_threads(args.threads)

    from railride import Suspension, scenario, simulate
    from railride.secondary.control import CONTROLLERS
    from railride.studies.league import league

    from railride.engine import kernels

    stepper: list[float] = []  # the CPU time of each kernel call in this thread
    run_parallel = kernels.run_parallel

    def timed(kernel, n_samples, *rest):
        t0 = time.thread_time()
        run_parallel(kernel, n_samples, *rest)
        stepper.append(time.thread_time() - t0)

    if args.threads == 1:  # one thread: the kernel runs in this thread, so its time is measurable
        kernels.run_parallel = timed

    def stepper_time(run) -> float:
        best = float("inf")
        for _ in range(args.repeat):
            stepper.clear()
            run()
            best = min(best, sum(stepper))
        return best

    sc = scenario("paper-sine")
    steps = round(sc.duration / 1e-4)
    laws = [n for n in CONTROLLERS if n != "passive"]
    times, cpu, alone = {}, {}, {}
    for name in laws:
        susp = Suspension.named(name)
        simulate(sc, None, susp)  # compile and warm
        times[name] = min_time(lambda: simulate(sc, None, susp).metrics(), args.repeat)
        cpu[name] = min_time(lambda: simulate(sc, None, susp).metrics(), args.repeat, time.process_time)
        if args.threads == 1:
            alone[name] = stepper_time(lambda: simulate(sc, None, susp))
    ref = times["sas-attitude-ride"]
    print(f"numba threads: {numba.get_num_threads()}\n")
    extra = " stepper alone, CPU per step |" if alone else ""
    head = "| law (MR dampers, 10 s, paper-sine) | time | per step | CPU time per step |"
    print(f"{head}{extra} / SAS (attitude+ride) |")
    print("|---|---|---|---|---|" + ("---|" if alone else ""))
    for name in laws:
        t, c = times[name], cpu[name]
        own = f" {alone[name] / steps * 1e6:.3f} us |" if alone else ""
        row = f"| {name} | {t * 1e3:.1f} ms | {t / steps * 1e6:.3f} us | {c / steps * 1e6:.3f} us |"
        print(f"{row}{own} {t / ref:.2f} |")
    if args.no_league:
        return

    chosen = ["pid", "sas-attitude-ride", "skyhook", "groundhook", "clipped-optimal"]
    run = lambda: league(["paper-sine", "fra4", "german-low"], [30.0, 55.56], controllers=chosen)  # noqa: E731
    run()  # warm
    t = min_time(run, max(1, args.repeat // 2))
    print(f"\nleague table, {len(chosen)} controllers x 3 scenarios x 2 speeds (with both bounds), warm: {t:.2f} s")


def vehicles(args) -> None:
    """Time per step of the rigid, stopped and flexible vehicles (see the module's docstring)."""
    import numba

    if args.threads > 0:
        numba.set_num_threads(args.threads)
    from railride import Suspension, VehicleParams, scenario, simulate

    paper = VehicleParams.preset("paper")
    cars = {
        "rigid": paper,
        "bump stops": paper.replace(k_stop=2.0e6),
        "bending 10 Hz": paper.replace(L_c=24.0, f_bend=10.0),
    }
    sc = scenario("paper-sine")
    steps = round(sc.duration / 1e-4)
    print(f"numba threads: {numba.get_num_threads()}\n")
    print("| law | vehicle | one run, per step | / rigid | 16 runs (lanes), per sample-step | / rigid |")
    print("|---|---|---|---|---|---|")
    for law in ("sas-attitude-ride", "skyhook"):
        susp = Suspension.named(law)
        base = None
        for name, car in cars.items():
            simulate(sc, car, susp)  # compile and warm
            simulate([sc] * 16, car, susp)
            one = min_time(lambda: simulate(sc, car, susp), args.repeat, time.process_time) / steps
            many = min_time(lambda: simulate([sc] * 16, car, susp), args.repeat, time.process_time) / (16 * steps)
            base = base or (one, many)
            print(
                f"| {law} | {name} | {one * 1e6:.3f} us | {one / base[0]:.2f} "
                f"| {many * 1e6:.3f} us | {many / base[1]:.2f} |"
            )


if __name__ == "__main__":
    main()
