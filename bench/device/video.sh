#!/bin/bash
# Device check of the video's warm frames on the GPU backend (bench/device/video_frames_gpu.py) and the GPU tests.
# On the lent machine, from the repository root, after bench/device/prepare.sh here (carry .gpu):
#     bash bench/device/video.sh      (writes under $OUT; FRAMES, T_TESTS, T_VIDEO adjust it)
source bench/device/setup.sh

log tests
timeout ${T_TESTS:-120} $PY -m pytest -q -p no:cacheprovider tests/test_gpu.py tests/test_deformation.py \
  tests/test_objective.py > "$OUT/pytest.log" 2>&1
tail -3 "$OUT/pytest.log"

log video
timeout ${T_VIDEO:-300} $PY bench/device/video_frames_gpu.py --frames ${FRAMES:-8} --json "$OUT/video-gpu.json" \
  2>&1 | tee "$OUT/video-gpu.log"
log done
