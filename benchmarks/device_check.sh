#!/usr/bin/env bash
# The GPU and 16-core measurements of docs/gpu.md and docs/performance.md in one prepared run,
# for a lent machine with one NVIDIA GPU and 16 cores, no network, and numba, numba-cuda,
# numpy, scipy, xarray, pandas, typer and rich already installed (the package runs from this
# tree through PYTHONPATH; nothing is installed).
#
# Run:  bash benchmarks/device_check.sh [BUDGET_S]      (default 580 s in all)
#       bash benchmarks/device_check.sh --gpu [BUDGET_S]  (steps 1 to 10: the GPU's and the designs)
#       bash benchmarks/device_check.sh --kernels [BUDGET_S]  (the machine, then the kernel's builds: below)
#       bash benchmarks/device_check.sh --smoke          (here: the simulator, tiny sizes, a check of the script)
#       SKIP=gpu-builds,design bash benchmarks/device_check.sh --gpu 300  (a second call: the steps
#       named in SKIP, comma-separated as the log's "## NAME" lines name them, are left out)
#
# --kernels: builds of the GPU kernel (bench_gpu_kernel.py --kernels) timed on 1,024, 8,192 and
# 32,768 SAS closed loops: special-lean (9.21e8 sample-steps/s at 32,768 on an H100, 2026-11-27)
# against special-lean-n1 (the Bouc-Wen exponent known to the compile) and
# special-lean-n1-sparse, the default since (the vehicle matrices' zeros left out too; neither
# timed yet); Nsight Compute on one launch of the first and the last on 32,768 runs (where the
# image has ncu); the GPU tests on the device (the general kernel: a build for every case of the
# tests would compile a dozen kernels); the default design on the GPU (cut at 150 s); the
# default build under register limits of 168 and 128 with what the budget leaves.
#
# Steps, most wanted first; each gets at most its cap and what is left of the budget, and one
# that runs out is cut and said so in the log, so the run ends inside the budget:
#   1. the machine: GPU, driver, cores (and whether they are threads of fewer cores), versions,
#      a profiler (nsys, ncu) if there is one, and whether railride sees a usable GPU
#   2. the default build of the kernel against the one timed on 2026-11-27 (bench_gpu_kernel.py
#      --kernels), 1,024 and 32,768 SAS closed loops: the 1e9 target, and whether their runs are
#      the same on the device
#   3. the default design with backend auto (the tuning rounds that step sooner on the GPU go
#      there, by solver.gpu_pays, the rest on the CPU's cores), as a user runs it: its wall and
#      CPU time, its stepping rate, and by stage how long some batch stepped and how long none did
#   4. 1e5 metrics-only runs of 60 s in one call (bench_gpu.py --only-metrics): whether they fit
#      one GPU's memory, never measured
#   5. the default design with --backend gpu, every GPU kernel compiled in the run, as a user
#      first meets it (the CPU's kernels compiled first, as an install does: bench_design.py
#      --profile, cut at 150 s: the target of 2 minutes and start-up; one that is cut prints what
#      it had done by then)
#   6. bench_gpu.py: 32,768 SAS closed loops on the GPU (and how long its first call, which
#      compiles the kernel, takes), their agreement with the CPU over 64 samples, the same batch
#      on the CPU's cores, and the metrics-only batch of the studies
#   7. bench_gpu_kernel.py --blocks 32,64,128: the kernel on 1,024, 2,048 and 8,192 runs in
#      blocks of 32, 64 and 128 threads (a design's rounds last a lone thread's time)
#   8. bench_gpu_cache.py: whether numba-cuda's file cache keeps the kernel between processes,
#      and the compile each process would save; then the design with --backend gpu and its
#      kernels in that cache (gpu.FILE_CACHE), filled first by a small design of the same kinds
#      of batch, cut at 200 s
#   9. bench_gpu_kernel.py --concurrent 8: eight 32-run batches from eight threads at once against
#      one after another (a design's held-out runs): whether calls on their own streams overlap;
#      then, where the image has Nsight Compute (ncu), one launch of 1,024 runs profiled
#  10. the GPU tests of tests/physics on the device, every build the cases make (the general
#      kernel's passed there on 2026-11-27)
#  11. bench_gil.py --threads <cores>: how much of a study chunk's work beside its stepping runs
#      in parallel when every core has a chunk (measured on 2 cores only)
#  12. the CPU's figures, measured once on 16 cores already (2026-11-27): bench_study.py (the 1,000-run study
#      on 2 cores, on all cores, also with 1 chunk ahead, in one process per core and in four
#      processes of a quarter of the cores each; Dask clusters of 1 and 8 workers of 2 threads,
#      where the image has dask.distributed), and
#      bench_dampers.py --lane-sizes (run_batch against the lane stepper, 1 to 16 threads)
# Everything printed goes to $OUT/device_check.log as well (the device tool brings $OUT back).
# No figure is written anywhere else: copy the rows into the docs with the machine and date.
set -u
cd "$(dirname "$0")/.."
SMOKE=0
GPU_ONLY=0
KERNELS_ONLY=0
BUDGET=580
if [ "${1:-}" = "--gpu" ]; then GPU_ONLY=1; shift; fi
if [ "${1:-}" = "--kernels" ]; then KERNELS_ONLY=1; shift; fi
if [ "${1:-}" = "--smoke" ]; then SMOKE=1; BUDGET=900; elif [ -n "${1:-}" ]; then BUDGET=$1; fi
OUT=${OUT:-/tmp/railride_device_check}
mkdir -p "$OUT"
LOG="$OUT/device_check.log"
: >"$LOG"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1
PY=${PYTHON:-python3}
if [ "$SMOKE" = 1 ]; then
  export NUMBA_ENABLE_CUDASIM=1
  PY=${PYTHON:-.venv/bin/python}
else
  export NUMBA_ENABLE_CUDASIM=0
fi
START=$(date +%s)

# step NAME CAP_S COMMAND...: run it with what is left of the budget, at most CAP_S
step() {
  local name=$1 cap=$2
  shift 2
  local left=$((BUDGET - ($(date +%s) - START)))
  local t=$((cap < left ? cap : left))
  echo "" | tee -a "$LOG"
  echo "## $name (at $(($(date +%s) - START)) s; at most $t s)" | tee -a "$LOG"
  case ",${SKIP:-}," in
  *",$name,"*)
    echo "skipped: named in SKIP" | tee -a "$LOG"
    return
    ;;
  esac
  if [ "$t" -lt 10 ]; then
    echo "skipped: the budget is spent" | tee -a "$LOG"
    return
  fi
  echo "\$ $*" | tee -a "$LOG"
  local t0=$(date +%s)
  timeout -k 5 "$t" "$@" 2>&1 | tee -a "$LOG"
  local rc=${PIPESTATUS[0]}
  local took=$(($(date +%s) - t0))
  if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
    printf "\ncut: still running after %s s (its limit)\n" "$took" | tee -a "$LOG"  # on a line of its own
  else
    echo "exit $rc after $took s" | tee -a "$LOG"
  fi
}

if [ "$SMOKE" = 1 ]; then
  GPU_SAMPLES=16 DURATION=0.005 CHECK=4 SEEDS=1 THREADS=1,2 SIZES=8,16
else
  GPU_SAMPLES=32768 DURATION=1 CHECK=64 SEEDS=20 THREADS=1,2,4,8,16 SIZES=8,16,32,64,128,256
fi
CORES=$(nproc)

step machine 30 bash -c "date -u; nproc; (lscpu | grep -E 'Model name|Thread|Core|Socket|NUMA node\(s\)' || true); (nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv || echo 'no nvidia-smi'); (command -v nsys ncu || echo 'no nsys or ncu on the PATH'); \
$PY -c 'import sys, numpy, scipy, numba; print(sys.version.split()[0], \"numpy\", numpy.__version__, \"scipy\", scipy.__version__, \"numba\", numba.__version__)'; \
$PY -c 'import importlib.metadata as m; print(\"numba-cuda\", m.version(\"numba-cuda\"))' || echo 'no numba-cuda'; \
$PY -c 'import os; from railride.run.solver import gpu_missing; sim = os.environ.get(\"NUMBA_ENABLE_CUDASIM\") == \"1\"; print((\"railride sees a usable GPU\" + (\" (the CUDA simulator: --smoke)\" if sim else \"\")) if gpu_missing() is None else \"railride: \" + gpu_missing())'"

# each step and how it ended, at the end of the log (the device tool returns the last 12,000 characters)
finish() {
  echo "" | tee -a "$LOG"
  echo "done in $(($(date +%s) - START)) s of a $BUDGET s budget" | tee -a "$LOG"
  echo "" | tee -a "$LOG"
  echo "## summary" | tee -a "$LOG"
  grep -E '^## |^exit [0-9]+ after|^cut: |^skipped: ' "$LOG" | grep -v '^## summary' | paste - - | tee -a "$LOG"
}

if [ "$KERNELS_ONLY" = 1 ]; then
  if [ "$SMOKE" = 1 ]; then  # the simulator times nothing: the kernels' resources instead, and a small design
    step gpu-kernel-builds 200 env NUMBA_ENABLE_CUDASIM=0 $PY benchmarks/bench_gpu_kernel.py --resources \
      --registers none --kernels special-lean,special-lean-n1-sparse
    step design-on-gpu 30 $PY benchmarks/bench_design.py --profile --backend gpu --gpu-kernel special-lean-n1-sparse \
      --controllers pid --budget 25 --duration 0.05
    finish
    exit 0
  fi
  step gpu-kernel-builds 200 $PY benchmarks/bench_gpu_kernel.py \
    --kernels special-lean,special-lean-n1,special-lean-n1-sparse \
    --registers none --samples 1024,8192,32768
  for k in special-lean special-lean-n1-sparse; do
    if command -v ncu >/dev/null 2>&1; then
      step "gpu-ncu-$k" 75 ncu --section LaunchStats --section Occupancy --section SpeedOfLight \
        --section MemoryWorkloadAnalysis --section WarpStateStats -k regex:_kernel -c 1 \
        $PY benchmarks/bench_gpu_kernel.py --profile-run --samples 32768 --kernels "$k"
    else
      step "gpu-ncu-$k" 10 echo "no ncu on the PATH: the kernel not profiled"
    fi
  done
  step gpu-tests 100 $PY -m pytest -q -p no:randomly -p no:cacheprovider -k "not specialised" \
    tests/physics/test_gpu.py tests/physics/test_gpu_metrics.py
  step design-on-gpu 150 $PY benchmarks/bench_design.py --profile --backend gpu
  step gpu-kernel-registers 80 $PY benchmarks/bench_gpu_kernel.py --kernels special-lean-n1-sparse --registers 168,128 \
    --samples 8192,32768
  finish
  exit 0
fi

if [ "$SMOKE" = 1 ]; then  # the simulator times nothing: the script's steps at tiny sizes
  step gpu-throughput 90 $PY benchmarks/bench_gpu.py --samples "$GPU_SAMPLES" --duration "$DURATION" --cpu --check "$CHECK" --metrics-only
  step design 60 $PY benchmarks/bench_design.py --profile --controllers pid --budget 25 --duration 0.5
  step gpu-kernel 60 env NUMBA_ENABLE_CUDASIM=0 $PY benchmarks/bench_gpu_kernel.py --resources --registers none \
    --kernels special-lean-n1-sparse
  step gpu-cache 150 $PY benchmarks/bench_gpu_cache.py
  step gpu-only-metrics 60 $PY benchmarks/bench_gpu.py --samples 8 --duration 0.01 --only-metrics
else
  # the default build (the Bouc-Wen exponent and the matrices' zeros known to the compile, never
  # timed) against the build timed at 9.21e8 on 2026-11-27: their rates and whether their runs
  # are the same to the bit on the device
  step gpu-builds 120 $PY benchmarks/bench_gpu_kernel.py --kernels special-lean,special-lean-n1-sparse \
    --registers none --samples 1024,32768
  # the CPU kernels compiled once into numba's cache, as an install compiles them into the package,
  # so that no timed step below is cut by compiling them
  step compile-cpu 90 $PY -c "from railride.studies.study import study; \
study(['pid', 'sas-attitude', 'sas-attitude-ride', 'clipped-optimal'], track_seeds=[0], speeds=[40.0], duration=1.0)"
  # the default design as a user runs it (backend auto: each batch where it steps sooner, by
  # solver.gpu_pays: the tuning rounds from about 850 runs on the GPU, the rest on the 16 cores),
  # its GPU kernels compiled in the run: "exit 0 after N s" is its time with start-up; cut at the
  # cap, it prints what it had done
  step design 150 $PY benchmarks/bench_design.py --profile
  # 1e5 runs of 60 s that keep only their metrics, in one call: whether they fit one GPU's memory
  # (computed so far: 0.47 GiB of runs' own arrays), its device and host peaks, its rate
  step gpu-1e5-metrics 200 $PY benchmarks/bench_gpu.py --samples 100000 --duration 60 --only-metrics
  # the default design on the GPU as a user first meets it: every GPU kernel compiled in the run (cut
  # at 150 s twice on the H100 when a compile took 19 to 43 s; its front end now takes 1.6 to 12 s
  # a build on a 2-core VM, docs/gpu.md). Cut at the cap (SIGTERM), it prints what it had done by then
  step design-on-gpu 150 $PY benchmarks/bench_design.py --profile --backend gpu
  # 32,768 runs: the first call's compile, agreement with the CPU over 64 samples, the same batch
  # on the CPU's cores, the studies' metrics-only batch
  step gpu-throughput 90 $PY benchmarks/bench_gpu.py --samples "$GPU_SAMPLES" --duration "$DURATION" --cpu --check "$CHECK" --metrics-only
  # small batches in small blocks: a design's rounds (256 to 2,048 runs) last a lone thread's time
  step gpu-kernel-blocks 120 $PY benchmarks/bench_gpu_kernel.py --kernels special-lean-n1-sparse --registers none \
    --blocks 32,64,128 --samples 1024,2048,8192
  # whether numba-cuda's file cache keeps the kernel between processes, and the compile it saves
  step gpu-cache 150 $PY benchmarks/bench_gpu_cache.py
  # the design with its kernels in numba's file cache, as a second design on the machine finds
  # them; a small design first meets the same kinds of batch and fills the cache
  step design-on-gpu-fill 150 $PY benchmarks/bench_design.py --profile --backend gpu --gpu-file-cache \
    --budget 25 --duration 0.05
  step design-on-gpu-cached 200 $PY benchmarks/bench_design.py --profile --backend gpu --gpu-file-cache
  step gpu-concurrent 60 $PY benchmarks/bench_gpu_kernel.py --concurrent 8 --duration 2
  # where a small batch's time goes (Nsight Compute, where the image has it): one launch of 1,024 runs
  if command -v ncu >/dev/null 2>&1; then
    step gpu-ncu 120 ncu --section LaunchStats --section Occupancy --section SpeedOfLight \
      --section MemoryWorkloadAnalysis --section WarpStateStats -k regex:_kernel -c 1 \
      $PY benchmarks/bench_gpu_kernel.py --profile-run --samples 1024 --kernels special-lean-n1-sparse
  else
    step gpu-ncu 10 echo "no ncu on the PATH: the kernel not profiled"
  fi
fi

# run once on a device (2026-11-27, the general kernel): now with every build the cases make
step gpu-tests 120 $PY -m pytest -q -p no:randomly -p no:cacheprovider tests/physics/test_gpu.py tests/physics/test_gpu_metrics.py

# the CPU's figures (measured on a lent 16-core machine on 2026-11-27: docs/performance.md)
if [ "$GPU_ONLY" = 0 ]; then

# how much of a chunk's work beside its stepping runs in parallel on every core (never measured
# on more than 2): the share that does not bounds a study in threads
if [ "$SMOKE" = 1 ]; then
  step gil 60 $PY benchmarks/bench_gil.py --threads 2 --duration 1 --repeat 1
else
  step gil 90 $PY benchmarks/bench_gil.py --threads "$CORES" --duration 5 --repeat 3
fi

if [ "$SMOKE" = 1 ]; then
  step study-2-cores 120 $PY benchmarks/bench_study.py --seeds "$SEEDS" --duration 1 --profile
else
  step study-2-cores 60 env NUMBA_NUM_THREADS=2 taskset -c 0,1 $PY benchmarks/bench_study.py --seeds "$SEEDS" --profile
  step study-all-cores 45 $PY benchmarks/bench_study.py --seeds "$SEEDS" --profile --held
  # a 32-run chunk on the lane stepper holds 4 of 16 threads: the default (chunks_ahead, 4 chunks
  # ahead on 16 threads) against the one chunk ahead of before, which held at most 8
  step study-all-cores-ahead-1 30 $PY benchmarks/bench_study.py --seeds "$SEEDS" --ahead 1 --profile --held
  step study-processes 60 $PY benchmarks/bench_study.py --seeds "$SEEDS" --processes "$CORES" --profile
  # four processes of four threads: a chunk's Python work split four ways, its 4 lane groups on
  # the process's own threads, each track's tables made four times instead of sixteen
  step study-processes-4 45 $PY benchmarks/bench_study.py --seeds "$SEEDS" --processes 4 --profile
  # N Dask workers against one with the same numba threads (2 each): measured for N = 2 only
  if $PY -c "import distributed" 2>/dev/null; then
    step dask-1-worker 60 $PY benchmarks/bench_study.py --seeds "$SEEDS" --dask --workers 1 --worker-threads 2
    step dask-8-workers 60 $PY benchmarks/bench_study.py --seeds "$SEEDS" --dask --workers 8 --worker-threads 2
  else
    step dask 10 echo "no dask.distributed in this image: the cluster not measured"
  fi
fi
step lane-sizes 90 $PY benchmarks/bench_dampers.py --lane-sizes --repeat 3 --threads "$THREADS" --sizes "$SIZES"
fi

finish
