#!/usr/bin/env bash
# `incal gfimu solve` at real length, in one run: a simulated 10^6-sample
# motion (1 kHz, 1000 s) of the twelve-accelerometer layout, solved to CSV,
# JSON and JSON lines; wall time and peak memory of each (GNU time), and
# the paper's six-accelerometer layout on the same motion, which stops
# where its feedback diverges. Not run by CI.
#
#   scripts/bench-gfimu.sh
#
# The data live in ${INCAL_BENCH_DIR:-${TMPDIR:-/tmp}/incal-bench}.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR="${INCAL_BENCH_DIR:-${TMPDIR:-/tmp}/incal-bench}"
mkdir -p "$DIR"
cargo build --release --quiet -p incal-cli
INCAL="$(pwd)/${CARGO_TARGET_DIR:-target}/release/incal"
cd "$DIR"
MOTION=(--kind motion --duration-s 999.999 --rate-hz 1000 --spin-up-s 1.0005 --seed 4)
for layout in twelve paper; do
  "$INCAL" simulate gfimu --layout "$layout" --seed 3 --samples 100 -o "static_$layout.csv"
  "$INCAL" gfimu calibrate --layout "$layout" --input "static_$layout.csv" --json -o "cal_$layout.json"
  /usr/bin/time -f "simulate ($layout): %e s, peak %M KB" \
    "$INCAL" simulate gfimu --layout "$layout" "${MOTION[@]}" -o "motion_$layout.csv"
done
SIZE=$(stat -c %s motion_twelve.csv)
echo "motion file (twelve): $((SIZE / 1000000)) MB, $(($(grep -vc "^#" motion_twelve.csv) - 1)) samples"
for out in "" --json --jsonl; do
  /usr/bin/time -f "solve twelve ${out:-csv}: %e s, peak %M KB" \
    "$INCAL" gfimu solve --layout twelve --calibration cal_twelve.json \
    --input motion_twelve.csv $out -o "solution_twelve${out:-.csv}"
done
/usr/bin/time -f "solve paper (feedback): %e s, peak %M KB" \
  "$INCAL" gfimu solve --calibration cal_paper.json --input motion_paper.csv \
  -o solution_paper.csv || echo "(the paper's layout stops where its feedback diverges: exit $?)"
