#!/bin/bash
# Packs what a lent GPU machine (no network, Python 3.12, CUDA 13, CuPy) needs for bench/device/check.sh into
# .gpu/ (ignored; carried by the device tool, under its 64 MiB limit): ducc0, finufft, cufinufft 2.5 (its
# library xz-compressed), CUDA 12's libcudart, a libcufft.so.11 that forwards cufinufft's five cuFFT calls to the
# machine's CUDA 13 cuFFT, the package as it was before issue 34 (the old of the paired bench) and the bench inputs.
# Run from the repository root here:  bash bench/device/prepare.sh [OLD_COMMIT]
set -eu
OLD=${1:-4bbe5f5}
PY=${PY:-.venv/bin/python}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
grep -qx "/.gpu/" .git/info/exclude 2>/dev/null || { mkdir -p .git/info && echo "/.gpu/" >> .git/info/exclude; }
rm -rf .gpu && mkdir -p .gpu/old "$WORK/site/cudalib"
platforms="--platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64"
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp $platforms \
  -d "$WORK/wheels" ducc0 finufft "cufinufft>=2.5" nvidia-cuda-runtime-cu12
for wheel in "$WORK"/wheels/{ducc0,finufft,cufinufft}-*.whl; do unzip -q -o "$wheel" -d "$WORK/site"; done
unzip -p "$WORK"/wheels/nvidia_cuda_runtime_cu12-*.whl nvidia/cuda_runtime/lib/libcudart.so.12 \
  > "$WORK/site/cudalib/libcudart.so.12"
xz -9 -T1 -c "$WORK/site/cufinufft/libcufinufft.so" > .gpu/libcufinufft.so.xz
rm "$WORK/site/cufinufft/libcufinufft.so"
tar -cJf .gpu/site.tar.xz -C "$WORK/site" .
gcc -O2 -shared -fPIC -o .gpu/libcufft.so.11 bench/device/cufft_shim.c \
  -Wl,--version-script=bench/device/cufft_shim.map -Wl,-soname,libcufft.so.11 -ldl
git archive "$OLD" stipple | tar -x -C .gpu/old
$PY -c "import sys; sys.path.insert(0, 'bench'); import paired, pathlib; paired.make_inputs(pathlib.Path('.gpu/inputs'))"
size=$(du -sb .gpu | cut -f1)
echo ".gpu: $((size / 1048576)) MiB (with the checkout it must stay under the device tool's 64 MiB)"
