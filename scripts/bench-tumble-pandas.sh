#!/usr/bin/env bash
# `incal tumble` against pandas on the same 720k-row tumble file (12
# positions x 60,000 samples), in one run: wall time of incal's whole
# reduction vs pandas' read_csv + groupby + least-squares fit, and incal's
# peak memory against the file size. Not run by CI. Needs python3 (venv),
# network access for pip, and GNU time (/usr/bin/time) for the peak RSS.
#
#   scripts/bench-tumble-pandas.sh
#
# The venv and the data live in ${INCAL_BENCH_DIR:-${TMPDIR:-/tmp}/incal-bench}.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR="${INCAL_BENCH_DIR:-${TMPDIR:-/tmp}/incal-bench}"
mkdir -p "$DIR"
if [ ! -x "$DIR/venv/bin/python" ] || ! "$DIR/venv/bin/python" -c "import pandas" 2>/dev/null; then
  python3 -m venv "$DIR/venv"
  "$DIR/venv/bin/pip" install --quiet pandas numpy
fi
PY="$DIR/venv/bin/python"
cargo build --release --quiet -p incal-cli
INCAL="${CARGO_TARGET_DIR:-target}/release/incal"
CSV="$DIR/tumble_720k.csv"
"$INCAL" simulate tumble --samples 60000 --noise 1e-5 --seed 1 -o "$CSV"
SIZE=$(stat -c %s "$CSV")

best() { # command...: best wall time of 5 runs (s)
  local b=1e9
  for _ in 1 2 3 4 5; do
    local t0 t1
    t0=$(date +%s.%N); "$@" > /dev/null; t1=$(date +%s.%N)
    b=$(echo "$t1 $t0 $b" | awk '{d = $1 - $2; print (d < $3) ? d : $3}')
  done
  echo "$b"
}

T_INCAL=$(best "$INCAL" tumble --mount pendulum --input "$CSV" --json)
RSS_KB=$( { /usr/bin/time -f "%M" "$INCAL" tumble --mount pendulum --input "$CSV" --json > /dev/null; } 2>&1 | tail -1 )
cat > "$DIR/pandas_tumble.py" <<'PYEOF'
import sys
import numpy as np
import pandas as pd
df = pd.read_csv(sys.argv[1], comment="#")
g = df.groupby("angle_deg")["output"].mean()
a = np.radians(g.index.to_numpy())
s, c = np.sin(a), np.cos(a)
# The tumble model's regressors (K0, K1, K2, K3, misalignment, K_ip) at 1 g.
A = np.column_stack([np.ones_like(s), s, s * s, s ** 3, c, s * c])
x, *_ = np.linalg.lstsq(A, g.to_numpy(), rcond=None)
print(x)
PYEOF
T_PANDAS=$(best "$PY" "$DIR/pandas_tumble.py" "$CSV")
# pandas in process: read_csv + groupby only, best of 5, interpreter and
# import excluded (the issue's yardstick; incal's figure is its whole process).
cat > "$DIR/pandas_inproc.py" <<'PYEOF'
import sys, time
import pandas as pd
best = 1e9
for _ in range(5):
    t0 = time.perf_counter()
    g = pd.read_csv(sys.argv[1], comment="#").groupby("angle_deg")["output"].mean()
    best = min(best, time.perf_counter() - t0)
print(best)
PYEOF
T_INPROC=$("$PY" "$DIR/pandas_inproc.py" "$CSV")
echo "file: $CSV ($((SIZE / 1000000)) MB, 720,000 rows)"
awk -v ti="$T_INCAL" -v tp="$T_PANDAS" -v tq="$T_INPROC" -v rss="$RSS_KB" -v size="$SIZE" 'BEGIN {
  printf "incal tumble (read + reduce + JSON)   %7.3f s   peak RSS %6.1f MB = %.2f x file\n", ti, rss / 1024, rss * 1024 / size
  printf "pandas read_csv + groupby + lstsq     %7.3f s   (interpreter start included)\n", tp
  printf "pandas read_csv + groupby, in process %7.3f s   (no interpreter, no fit, no hash)\n", tq
  printf "incal / pandas whole process          %7.2f\n", ti / tp
  printf "incal whole process / pandas in process %5.2f\n", ti / tq
}'
