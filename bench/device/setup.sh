# Sourced by the device scripts (check.sh, video.sh) on the lent machine, from the repository root: unpacks the
# GPU stack carried in .gpu (bench/device/prepare.sh) and writes $OUT/machine.txt; sets R, OUT, PY, S and log().
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
