#!/usr/bin/env bash
# The device check (issues 42 and 49) in one go, for a session that has a machine with an NVIDIA GPU.
#
#   bash benchmarks/gpu_check.sh fetch   # here, with the package registry: the wheels the
#                                        # GPU image lacks, for its Python 3.12, into .whl/
#   bash benchmarks/gpu_check.sh         # there (carry .whl): install them, run the GPU
#                                        # tests on the device (not the simulator), then
#                                        # bench_gpu.py; logs into $OUT (or ./gpu_check_out)
#
# The GPU image has Python 3.12 with numba, numba-cuda and its CUDA toolkit, JAX, diffrax,
# SciPy, SymPy, pandas, pytest; it lacks dask/distributed (the test suite's fixtures import
# them), python-flint, and a numpy below 2.5. The project runs from the checkout
# (PYTHONPATH), not installed. Budget (15 device-minutes a session, the start included):
# the tests stop at 3 minutes, bench_loss.py at 2, bench_gpu.py at 170 s; run it with
# timeout_s 540, carry .whl.
set -euo pipefail
cd "$(dirname "$0")/.."

WHEELS=(
  "dask==2026.8.0" "distributed==2026.8.0" "locket==1.0.0" "partd==1.4.2" "tblib==3.2.2"
  "zict==3.0.0" "tornado==6.6.1" "python-flint==0.9.0" "importlib_metadata==10.2.0"
  "lazy-importer==0.1.0" "numpy==2.4.6"
)

if [ "${1:-}" = "fetch" ]; then
  # .whl/ is in .gitignore: the device tool sends it only when a run names it in carry
  mkdir -p .whl
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
    --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
    --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 \
    --platform manylinux1_x86_64 --platform any -d .whl "${WHEELS[@]}"
  du -sh .whl
  exit 0
fi

OUT=${OUT:-$PWD/gpu_check_out}
mkdir -p "$OUT"
PY=python3
$PY -c "import numpy, numba; print('image: numpy', numpy.__version__, 'numba', numba.__version__)" \
  2>&1 | tee "$OUT/image.txt" || true
if compgen -G ".whl/*.whl" > /dev/null; then
  $PY -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl
  export PYTHONPATH=/tmp/site:$PWD
  # the image's numba may refuse the carried numpy < 2.5: then use the image's numpy
  if ! $PY -c "import numba, numba.cuda" >> "$OUT/image.txt" 2>&1; then
    rm -rf /tmp/site/numpy /tmp/site/numpy-* /tmp/site/numpy.libs
    echo "carried numpy dropped: the image's numba refused it" | tee -a "$OUT/image.txt"
  fi
else
  export PYTHONPATH=$PWD
fi
export PYTHONUNBUFFERED=1
{
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv || true
  $PY -c "import numpy, numba, numba_cuda; print('numpy', numpy.__version__, 'numba', numba.__version__, 'numba-cuda', numba_cuda.__version__)"
  $PY -c "from ntc_design.simulate.gpu import gpu_available; print(gpu_available())"
} 2>&1 | tee "$OUT/device.txt"

# the GPU tests on the device: larger sizes (1,000 steps), the kernels' PTX included
status=0
NTC_GPU_TESTS=device timeout 180 $PY -m pytest -q -n 0 -p no:cacheprovider -o addopts="" \
  --durations=8 tests/simulate/test_cuda_kernels.py tests/simulate/test_gpu_run.py \
  tests/simulate/test_gpu_timevarying.py tests/simulate/test_gpu.py \
  tests/simulate/test_loss_cuda.py tests/simulate/test_loss_mc.py \
  tests/cli/test_runs.py::test_simulate_device_gpu_runs_where_the_fixture_says 2>&1 \
  | tee "$OUT/gpu_tests.log" || status=1

# lossy links (issue 49): the loss GPU kernels beside the lossless one and the CPU kernel
timeout 120 $PY benchmarks/bench_loss.py --quick --gpu 2>&1 | tee "$OUT/bench_loss.log" || status=1
timeout 170 $PY benchmarks/bench_gpu.py 2>&1 | tee "$OUT/bench_gpu.log" || status=1
exit $status
