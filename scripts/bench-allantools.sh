#!/usr/bin/env bash
# Time incal against allantools on the same data, in one run, and print the
# ratios. Not run by CI. Needs python3 (venv) and network access for pip.
#
#   scripts/bench-allantools.sh            # 1e6 and 1e7 octave, 1e5 all
#   INCAL_BENCH_BIG=1 scripts/bench-allantools.sh   # also 1e8 f64 end to end
#
# The venv lives in ${INCAL_BENCH_DIR:-${TMPDIR:-/tmp}/incal-bench} (outside
# the repository); the data files too.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR="${INCAL_BENCH_DIR:-${TMPDIR:-/tmp}/incal-bench}"
mkdir -p "$DIR"
if [ ! -x "$DIR/venv/bin/python" ]; then
  python3 -m venv "$DIR/venv"
  "$DIR/venv/bin/pip" install --quiet allantools numpy
fi
PY="$DIR/venv/bin/python"
cargo build --release --quiet -p incal-cli
cargo build --release --quiet -p incal --example noise_timing
TARGET="${CARGO_TARGET_DIR:-target}"
INCAL="$TARGET/release/incal"
TIMING="$TARGET/release/examples/noise_timing"

# Same data for both: white rate noise, f64le, tau0 = 1 s.
gen() { # samples file [bias instability deg/h]
  "$INCAL" simulate noise --quantity gyro --arw-deg-rth 1 --bias-instability-deg-h "${3:-10}" \
    --rate-hz 1 --duration-s "$1" --seed 1 --format f64le --output "$2"
  # The file's write-back must not run under the timings.
  sync
}

compare() { # file grid
  local f="$1" g="$2"
  "$TIMING" "$f" "$g" > "$DIR/incal.txt"
  "$PY" - "$f" "$g" "$DIR/incal.txt" <<'PYEOF'
import sys, time
import numpy as np
import allantools
f, grid, incal_file = sys.argv[1], sys.argv[2], sys.argv[3]
y = np.fromfile(f, dtype="<f8")
# Both from the phase: incal's timings start from its phase array, so
# allantools gets its own phase (data_type="phase"); the rate-to-phase
# conversion is outside both timings.
x = allantools.frequency2phase(y, 1.0)
inc = dict(l.split() for l in open(incal_file))
for name in ["oadev", "mdev", "ohdev", "totdev"]:
    fn = getattr(allantools, name)
    # Same grid as incal: octave m <= N/4 ("all": every m <= N/4).
    n = len(y) + 1
    mmax = (n - 1) // 4
    taus = [2**k for k in range(64) if 2**k <= mmax] if grid == "octave" else list(range(1, mmax + 1))
    if grid == "all" and name == "totdev":
        print(f"{len(y):>10} {grid:>6} {name:>7}  allantools skipped (hours)  incal {float(inc.get(name + '_fused', inc[name])):9.4f} s")
        continue
    t = time.perf_counter()
    fn(x, rate=1.0, data_type="phase", taus=np.array(taus, dtype=float))
    ta = time.perf_counter() - t
    ti = float(inc.get(name + "_fused", inc[name]))
    print(f"{len(y):>10} {grid:>6} {name:>7}  allantools {ta:9.4f} s  incal {ti:9.4f} s  ratio {ta/ti:7.1f}x")
PYEOF
}

for n in 1000000 10000000; do
  gen "$n" "$DIR/y$n.f64"
  compare "$DIR/y$n.f64" octave
done
gen 100000 "$DIR/y100000.f64"
compare "$DIR/y100000.f64" all

if [ "${INCAL_BENCH_BIG:-0}" = 1 ]; then
  # White rate noise and bias instability, as above (the flicker
  # generator needs about 9 GB and half a minute here).
  gen 100000000 "$DIR/y1e8.f64"
  run_incal() {
    /usr/bin/time -f "%e s %M KB" -o "$DIR/time.txt" "$INCAL" noise --input "$DIR/y1e8.f64" \
      --format f64le --channels 1 --rate-hz 1 --quiet --json > /dev/null
    read -r secs _ kb _ < "$DIR/time.txt"
  }
  # One sequential read through a 16 MB user buffer (dd; cat may splice
  # to /dev/null without reading).
  read_once() { dd if="$DIR/y1e8.f64" of=/dev/null bs=16M 2>&1 | sed -n 's/.* copied, \([0-9.]*\) s.*/\1/p'; }
  size=$(stat -c %s "$DIR/y1e8.f64")
  if [ -w /proc/sys/vm/drop_caches ]; then
    echo 3 > /proc/sys/vm/drop_caches; cold_read=$(read_once)
    echo 3 > /proc/sys/vm/drop_caches; run_incal
    echo "1e8 f64, cold cache: sequential read $cold_read s; incal noise (all five deviations, CI, fit, hash) $secs s; peak RSS $((kb / 1024)) MiB for a $((size / 1048576)) MiB file"
  fi
  read_once > /dev/null
  warm_read=$(read_once)
  run_incal
  echo "1e8 f64, file cached: sequential read $warm_read s; incal noise $secs s; peak RSS $((kb / 1024)) MiB for a $((size / 1048576)) MiB file"
fi
