#!/bin/bash
# Device check: does the GPU path's thread count matter? (The million-dot GPU run spent 188 s of system time on 16
# threads, 2026-11-27.) Whole `stipple torus` commands on the cat photo, 1024², wall / user / sys seconds each.
# On the lent machine, from the repository root, after bench/device/prepare.sh here (carry .gpu):
#     bash bench/device/threads.sh      (writes under $OUT; SPECS="backend:threads:M ..." adjusts it)
source bench/device/setup.sh
TIMEFORMAT="wall %R user %U sys %S"
for spec in ${SPECS:-cufinufft:16:200000 cufinufft:4:200000 ducc0:16:200000 ducc0:4:200000 cufinufft:4:1000000 cufinufft:16:1000000}; do
  IFS=: read -r backend threads count <<< "$spec"
  log "$backend threads $threads M $count"
  echo "$backend threads $threads M $count" >> "$OUT/threads.log"
  { time timeout ${T_RUN:-240} $PY -m stipple torus .gpu/inputs/cat1024.png -M "$count" --backend "$backend" \
      --threads "$threads" -o "$OUT/dots-$backend-$threads-$count.csv" 2>&1 | tail -1; } 2>&1 | tee -a "$OUT/threads.log"
  rm -f "$OUT/dots-$backend-$threads-$count.csv"
done
log done
