"""The GPU kernel's resources and what they cost (railride.engine.gpu).

Run:  python benchmarks/bench_gpu_kernel.py --resources [--registers none,168,128,96] [--kernels general,lean]
      python benchmarks/bench_gpu_kernel.py [--registers none,128] [--kernels ...] [--blocks 32,128]
                                            [--samples 1024,32768] [--duration 1]
      python benchmarks/bench_gpu_kernel.py --concurrent 8 [--duration 2]
      ncu --set full -k regex:_kernel -c 1 python benchmarks/bench_gpu_kernel.py --profile-run

* ``--resources`` needs no GPU, only the gpu extra: the kernel compiled to PTX for an H100
  (compute capability 9.0) and assembled by ``ptxas -v`` (the gpu extra's, else the one on the
  PATH) under each register limit of ``--registers``: registers per thread, stack frame, spill
  stores and loads as ptxas reports them, and the occupancy that register count allows by the
  limits of compute capability 9.0 (NVIDIA, CUDA C++ Programming Guide, "Technical
  Specifications per Compute Capability": 65,536 registers, 64 warps and 32 blocks per
  multiprocessor; registers given to a warp in units of 256). A driver's own compile of the PTX
  may differ from this ptxas's. Where nvdisasm is found (``NVDISASM``, else the PATH; the gpu
  extra has none, NVIDIA's nvidia-cuda-nvdisasm wheel has one), the assembled kernel's machine
  instructions are counted too: all, local loads and stores, global loads, branches and calls,
  each as written once in the code (static counts, not how often they run).
* ``--resources --keys "[(law, faults, sensing, lean, unit_n, pattern), ...]"``: the build each
  of these kernel keys names (`gpu.kernel_key`: a key holds every constant of its compile) in
  place of ``--kernels``, in one process, one after another, as a process meets them: the kinds
  of batch a design sends the GPU (`bench_gpu.py --host-only` prints them), and what their
  compiles take on this machine.
* ``--kernels``: which builds of the kernel (`gpu_kernel._kernel_for`): ``general`` (the one for any
  batch), ``special`` (the damper law fixed, faults and sensing left out: the batches below),
  ``lean`` (one RK4 stage rate and a running sum), ``special-lean``, ``special-lean-n1`` (also
  the Bouc-Wen exponent n = 1 known to the compile, `gpu.UNIT_N`) and ``special-lean-n1-sparse``
  (the package's default: also only the terms of the q'' product, the corner deflections and
  the rail forcing that are not 0, `gpu.SPARSE_PRODUCT`); each under each limit.
* ``--blocks 32,64,128``: each size also launched in blocks of that many threads (default: the
  package's `gpu.THREADS_PER_BLOCK`, 128). A small batch in small blocks spreads over more
  multiprocessors, so fewer of its warps share each one's L1 (whether that pays: not yet timed).
* With a GPU, the same register limits on batches of ``--samples`` SAS closed loops
  (`bench_gpu._batch`): the kernels' seconds, sample-steps per second, the kernels' time per
  step (what one thread takes per step where all the batch's threads are resident at once),
  and the largest difference from the first limit's runs (none expected: a limit moves values
  between registers and memory, not the arithmetic).
* ``--concurrent K`` (GPU): K batches of 32 runs, as a study's chunks in flight send them (a
  design's held-out runs with their comfort), from K threads at once and then one after another:
  whether the kernels of calls on their own streams overlap on the device.
* ``--profile-run`` (GPU): one launch of the kernel (the first of ``--kernels``) on ``--samples``
  runs (the first size given) of 0.01 s and nothing else, for a profiler to attach to (NVIDIA
  Nsight Compute, ``ncu``: where its time goes, occupancy, memory traffic and what its warps
  wait on).
Prints Markdown rows for docs/gpu.md with the device and date. No test asserts timings.
"""

from __future__ import annotations

import argparse
import ast
import datetime
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

# compute capability 9.0 (CUDA C++ Programming Guide, technical specifications)
REGISTERS_PER_SM = 65536
WARPS_PER_SM = 64
BLOCKS_PER_SM = 32
REGISTER_UNIT = 256  # registers are given to a warp in units of this many
#: the histories compared between runs
CHANNELS = ("carbody_bounce", "carbody_pitch", "carbody_roll")


def occupancy(registers: int, block: int) -> tuple[int, float]:
    """(resident blocks per multiprocessor, resident warps / the most) for a kernel of
    ``registers`` per thread in blocks of ``block`` threads, no shared memory."""
    warps = -(-block // 32)
    per_warp = -(-registers * 32 // REGISTER_UNIT) * REGISTER_UNIT
    blocks = min(BLOCKS_PER_SM, WARPS_PER_SM // warps, (REGISTERS_PER_SM // per_warp) // warps)
    return blocks, blocks * warps / WARPS_PER_SM


def _limits(text: str) -> list[int | None]:
    return [None if v.strip().lower() in ("none", "0", "") else int(v) for v in text.split(",")]


def _ptxas() -> str:
    try:
        import nvidia.cuda_nvcc  # the gpu extra's toolkit (nvidia-cuda-nvcc-cu12)

        shipped = Path(list(nvidia.cuda_nvcc.__path__)[0]) / "bin" / "ptxas"
        if shipped.exists():
            return str(shipped)
    except ImportError:
        pass
    found = shutil.which("ptxas")
    if found is None:
        sys.exit("bench_gpu_kernel: no ptxas (install railride[gpu], which brings one)")
    return found


#: build -> (gpu.SPECIALISE, gpu.LEAN_RK4, gpu.UNIT_N, gpu.SPARSE_PRODUCT)
KERNELS = {
    "general": (False, False, False, False),
    "special": (True, False, False, False),
    "lean": (False, True, False, False),
    "special-lean": (True, True, False, False),
    "special-lean-n1": (True, True, True, False),
    "special-lean-n1-sparse": (True, True, True, True),
}


def use_build(name: str) -> None:
    """Set `railride.engine.gpu`'s build settings to those of ``name`` (`KERNELS`)."""
    from railride.engine import gpu

    gpu.SPECIALISE, gpu.LEAN_RK4, gpu.UNIT_N, gpu.SPARSE_PRODUCT = KERNELS[name]


def _kernels(text: str) -> list[str]:
    names = text.split(",")
    unknown = [k for k in names if k not in KERNELS]
    if unknown:
        sys.exit(f"bench_gpu_kernel: --kernels {','.join(unknown)}: not one of {', '.join(KERNELS)}")
    return names


def _key(name: str) -> tuple:
    """The kernel key (`gpu.kernel_key`) of build ``name`` for the benchmark's batches: Bouc-Wen,
    SAS, healthy, exact sensing."""
    from railride.engine import gpu
    from railride.engine.layout import LAW_BOUC_WEN, N_FAULT_COLS
    from railride.model.vehicle import Vehicle
    from railride.run.inputs import _system_arrays
    from railride.secondary.suspension import Suspension

    use_build(name)
    # as bench_gpu's batches: the paper's vehicle and damper (n = 1)
    damper = Suspension.named("sas-attitude-ride").damper.pack()[None, :]
    matrices = _system_arrays(Vehicle("paper"), passive=False)
    A, TS = matrices["A"][None], matrices["TS"][None]
    ftab = np.tile(gpu.BOGIE_ROWS, 4)[None, :].astype(float)  # the rails reach the bogies' rows
    faults, sensing = np.zeros((1, N_FAULT_COLS), np.int64), np.zeros((1, 3))
    return gpu.kernel_key(LAW_BOUC_WEN, faults, sensing, True, damper, A, TS, ftab)


def _resources(limits, kernels) -> None:
    from railride.engine import gpu

    if gpu.simulated():
        sys.exit("bench_gpu_kernel: --resources compiles for a GPU: run it with NUMBA_ENABLE_CUDASIM=0")
    ptxas = _ptxas()
    version = subprocess.run([ptxas, "--version"], capture_output=True, text=True).stdout.strip().splitlines()[-1]
    print(f"ptxas: {version}; sm_90; {datetime.date.today().isoformat()}")
    disasm = os.environ.get("NVDISASM") or shutil.which("nvdisasm")
    print(f"nvdisasm: {disasm or 'none (NVDISASM or the PATH): no SASS counts'}")
    print(
        "\n| kernel | register limit | registers | stack frame | spill stores | spill loads "
        "| blocks of 128 per SM | occupancy | PTX made in | SASS instructions | local loads / stores "
        "| global loads | branches | calls |"
    )  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    made = 0.0
    for name, key in kernels:
        t0 = time.perf_counter()
        code = gpu.ptx((9, 0), key)
        took = time.perf_counter() - t0
        made += took
        _assemble(ptxas, code, limits, name, took, disasm)
    print(f"\nPTX of the {len(kernels)} kernel(s), one after another in this process: {made:.1f} s")


def _sass_counts(disasm, cubin) -> str:
    """The kernel's machine instructions as nvdisasm lists them (static counts, each written
    instruction once: not how often it runs): all, LDL / STL, LDG, BRA and CALL."""
    if not disasm:
        return "| - | - | - | - | - |"
    text = subprocess.run([disasm, "-c", str(cubin)], capture_output=True, text=True, check=True).stdout
    ops = [m.group(1) for m in re.finditer(r"/\*[0-9a-f]{4,}\*/\s+(?:@!?U?P\w+\s+)?([A-Z][A-Z0-9_]*)", text)]
    n = {op: ops.count(op) for op in ("LDL", "STL", "LDG", "BRA", "CALL")}
    return f"| {len(ops)} | {n['LDL']} / {n['STL']} | {n['LDG']} | {n['BRA']} | {n['CALL']} |"


def _assemble(ptxas, code, limits, name, compiled, disasm=None) -> None:
    from railride.engine import gpu

    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "kernel.ptx"
        src.write_text(code)
        for limit in limits:
            cmd = [ptxas, "-v", "-arch=sm_90", str(src), "-o", str(Path(tmp) / "kernel.cubin")]
            if limit is not None:
                cmd[2:2] = ["-maxrregcount", str(limit)]
            out = subprocess.run(cmd, capture_output=True, text=True, check=True).stderr
            kernel = out[out.index("_kernel") :]  # the kernel's lines, not a helper's
            regs = int(re.search(r"Used (\d+) registers", kernel).group(1))
            frame, stores, loads = re.search(
                r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", kernel
            ).groups()
            blocks, occ = occupancy(regs, gpu.THREADS_PER_BLOCK)
            print(
                f"| {name} | {'none' if limit is None else limit} | {regs} | {frame} B | {stores} B | {loads} B "
                f"| {blocks} | {occ * 100:.1f} % | {compiled:.1f} s " + _sass_counts(disasm, Path(tmp) / "kernel.cubin")
            )


def _timed(limits, kernels, sizes, duration: float, blocks=(None,)) -> None:
    from bench_gpu import _batch

    from railride.engine import gpu
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings

    on_gpu = SolverSettings(output_rate=200.0, backend="gpu")
    steps = round(duration / on_gpu.dt)
    print(f"{gpu.device_name()}; {os.cpu_count()} CPU cores; {datetime.date.today().isoformat()}")
    print(
        "\n| kernel | register limit | compile | samples | threads a block | kernels | sample-steps/s "
        "| kernel time per step (us) | largest difference from the first |"
    )  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    first: dict = {}
    default_block = gpu.THREADS_PER_BLOCK
    for name, limit in [(k, r) for k in kernels for r in limits]:
        use_build(name)
        gpu.MAX_REGISTERS = limit
        gpu._compiled.clear()
        gpu.THREADS_PER_BLOCK = default_block
        scs, susp = _batch(32, 0.01, "sas-attitude-ride")
        t0 = time.perf_counter()
        simulate(scs, suspension=susp, solver=on_gpu)
        compile_s = time.perf_counter() - t0
        for n, block in [(n, b) for n in sizes for b in blocks]:
            gpu.THREADS_PER_BLOCK = default_block if block is None else block
            scs, susp = _batch(n, duration, "sas-attitude-ride")
            ds = simulate(scs, suspension=susp, solver=on_gpu).dataset
            q = np.stack([ds[k].values for k in CHANNELS])
            k = gpu.last_call()["kernel_s"]
            ref = first.setdefault(n, q)
            diff = float(np.nanmax(np.abs(q - ref)) / np.nanmax(np.abs(ref)))
            print(
                f"| {name} | {'none' if limit is None else limit} | {compile_s:.1f} s | {n:,} "
                f"| {gpu.THREADS_PER_BLOCK} | {k:.3f} s "
                f"| {n * steps / k:.3g} | {k / steps * 1e6:.1f} | {diff:.1e} |"
            )


def _concurrent(k: int, duration: float) -> None:
    from concurrent.futures import ThreadPoolExecutor

    from bench_gpu import _batch

    from railride.engine import gpu
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings

    on_gpu = SolverSettings(output_rate=1000.0, backend="gpu")
    scs, susp = _batch(32 * k, duration, "sas-attitude-ride")
    batches = [(scs[32 * i : 32 * (i + 1)], susp) for i in range(k)]  # 32 runs each
    warm, susp = _batch(32, 0.01, "sas-attitude-ride")
    simulate(warm, suspension=susp, solver=on_gpu)  # compiles

    def run(batch):
        return simulate(batch[0], suspension=batch[1], solver=on_gpu)

    t0 = time.perf_counter()
    serial = [run(b) for b in batches]
    one_by_one = time.perf_counter() - t0
    t0 = time.perf_counter()
    with ThreadPoolExecutor(k) as pool:
        together = list(pool.map(run, batches))
    at_once = time.perf_counter() - t0
    same = all(
        np.array_equal(a.dataset[k].values, b.dataset[k].values) for a, b in zip(serial, together) for k in CHANNELS
    )
    print(f"{gpu.device_name()}; {os.cpu_count()} CPU cores; {datetime.date.today().isoformat()}")
    print(
        f"\n{k} batches of 32 SAS runs of {duration:g} s (histories at 1 kHz): one after another "
        f"{one_by_one:.2f} s, from {k} threads at once {at_once:.2f} s ({one_by_one / at_once:.1f}x); "
        f"the same runs: {same}"
    )


def _profile_run(n: int, kernel: str) -> None:
    from bench_gpu import _batch

    from railride.engine import gpu
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings

    use_build(kernel)
    scs, susp = _batch(n, 0.01, "sas-attitude-ride")
    simulate(scs, suspension=susp, solver=SolverSettings(output_rate=200.0, backend="gpu"))
    print(
        f"{gpu.device_name()}: one launch of the {kernel} kernel on {n} runs of 0.01 s; "
        f"kernels {gpu.last_call()['kernel_s']:.3f} s"
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--resources", action="store_true")
    ap.add_argument("--registers", default="none,168,128,96", help="register limits (none: the compiler's)")
    ap.add_argument("--kernels", default="general", help=f"builds of the kernel: {', '.join(KERNELS)}")
    ap.add_argument("--blocks", default="none", help="threads a block, comma-separated (none: gpu.THREADS_PER_BLOCK)")
    ap.add_argument("--samples", default="1024,32768", help="batch sizes, comma-separated")
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--concurrent", type=int, default=0)
    ap.add_argument("--profile-run", action="store_true")
    ap.add_argument(
        "--keys", default=None, help="--resources: kernel keys (a list of tuples, as bench_gpu.py --host-only prints)"
    )
    args = ap.parse_args()
    if args.resources:
        if args.keys:  # a key names its build whole
            builds = [(f"key {k[:5]}", tuple(k)) for k in ast.literal_eval(args.keys)]
        else:
            builds = [(name, _key(name)) for name in _kernels(args.kernels)]
        _resources(_limits(args.registers), builds)
        return
    from railride.engine import gpu

    missing = gpu.why_not()
    if missing is not None or gpu.simulated():
        sys.exit(f"bench_gpu_kernel: needs a GPU ({missing or 'not in the simulator'})")
    if args.concurrent:
        _concurrent(args.concurrent, args.duration)
        return
    if args.profile_run:
        _profile_run(int(args.samples.split(",")[0]), _kernels(args.kernels)[0])
        return
    sizes = [int(v) for v in args.samples.split(",")]
    _timed(_limits(args.registers), _kernels(args.kernels), sizes, args.duration, _limits(args.blocks))


if __name__ == "__main__":
    main()
