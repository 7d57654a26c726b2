#!/bin/bash
# Device check of the speed work: GPU backend tests, whole commands (old / new CPU / new GPU), per-iteration times.
# On the lent machine, from the repository root, after bench/device/prepare.sh here (carry .gpu):
#     bash bench/device/check.sh      (writes under $OUT; CASES, T_TESTS, T_PAIRED, T_RUN, ITERATIONS adjust it)
set -u
export PYTHONUNBUFFERED=1 PYTHONDONTWRITEBYTECODE=1
R=$(pwd)
OUT=${OUT:-/tmp/out}
PY=${PY:-python3}
S=/tmp/site
mkdir -p "$OUT"
log() { echo "== $(date +%T) $*" | tee -a "$OUT/stages.log"; }

log setup
if [ -z "${SKIP_SITE:-}" ]; then
  mkdir -p $S && tar -xJf .gpu/site.tar.xz -C $S && xz -dc .gpu/libcufinufft.so.xz > $S/cufinufft/libcufinufft.so
  cp .gpu/libcufft.so.11 $S/cudalib/
  # The CUDA 13 cuFFT that CuPy loads: the shim forwards cufinufft's CUDA 12 calls to it.
  export CUFFT_REAL=$($PY -c "
import cupy, cupy.fft
cupy.fft.fft(cupy.ones(8))
print(next(l.split()[-1] for l in open('/proc/self/maps') if 'libcufft.so' in l))")
  export LD_LIBRARY_PATH=$S/cudalib:${LD_LIBRARY_PATH:-}
  export PYTHONPATH=$S:$R
fi
{
  nvidia-smi -L; nproc; $PY --version; echo "CUFFT_REAL=${CUFFT_REAL:-}"
  $PY -c "from importlib.metadata import version as v; print([(n, v(n)) for n in ('numpy', 'scipy', 'ducc0', 'finufft', 'cufinufft', 'cupy-cuda13x', 'scikit-image', 'pillow', 'click')])"
  $PY -c "import cufinufft, cupy; print('cufinufft imports; devices:', cupy.cuda.runtime.getDeviceCount())"
} > "$OUT/machine.txt" 2>&1
cat "$OUT/machine.txt"

log tests
timeout ${T_TESTS:-120} $PY -m pytest -q -p no:cacheprovider tests/test_gpu.py tests/test_transforms.py \
  tests/test_objective.py tests/test_torus.py::test_backends_reach_the_same_energy > "$OUT/pytest.log" 2>&1
tail -3 "$OUT/pytest.log"

# -P: not the working directory (this checkout) first on the path, so the old package is the one imported.
OLD="env PYTHONPATH=${S}:$R/.gpu/old $PY -P -m stipple"
mkdir -p /tmp/paired && cp -r .gpu/inputs /tmp/paired/
for spec in ${CASES:-million:1 portrait:2}; do
  name=${spec%%:*}; repeats=${spec##*:}
  log "paired $name"
  timeout ${T_PAIRED:-330} $PY bench/paired.py --old "$OLD" --new "$PY -m stipple" --variant "gpu=--backend cufinufft" \
    --cases "$name" --repeats "$repeats" --out /tmp/paired --output "$OUT/paired-$name.json" 2>&1 | tee -a "$OUT/paired.log"
done

log "per-iteration"
timeout ${T_RUN:-120} $PY bench/run.py --backends ducc0,cufinufft --sections torus --iterations ${ITERATIONS:-8} \
  ${RUN_EXTRA:-} --output "$OUT/run.json" > "$OUT/run.log" 2>&1
tail -4 "$OUT/run.log"
log done
