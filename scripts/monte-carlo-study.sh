#!/usr/bin/env bash
# The figures of docs/src/monte-carlo.md, measured with the release binary:
#   1. linear procedures: the share of seeds whose every GUM interval is
#      validated with --monte-carlo auto (tumble test, rate-transfer test);
#   2. a constructed nonlinear case (K0 = p0/p1 with K1 known to ~30 %):
#      the coverage of the true K0 by the Monte Carlo intervals and by the
#      GUM interval.
#
#   scripts/monte-carlo-study.sh [SEEDS_LINEAR=100] [SEEDS_RATIO=200]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build -q --release -p incal-cli
I=target/release/incal
lin=${1:-100}
ratio=${2:-200}
w=$(mktemp -d)
trap 'rm -rf "$w"' EXIT

judge='import json,sys
d=json.load(sys.stdin); m=d["monte_carlo"]
print(int(all(c["validated"] for c in m["coefficients"].values())), m["trials"])'
t=0; g=0
for s in $(seq 1 "$lin"); do
    $I simulate tumble --k1 10 --k0 0.01 --k2 0 --k3 0 --delta-o-arcsec 0 --delta-p-arcsec 0 \
        --k-ip 0 --k-io 0 --noise 1e-4 --samples 10 --seed "$s" -o "$w/t.csv"
    v=$($I tumble --input "$w/t.csv" --mount pendulum --json --monte-carlo auto --seed "$s" | python3 -c "$judge")
    t=$((t + ${v%% *}))
    $I simulate gyro-rate --samples 10 --seed "$s" -o "$w/g.csv"
    v=$($I gyro rate --input "$w/g.csv" --latitude-deg 45 --rate-uncertainty-ppm 20 --json \
        --monte-carlo auto --seed "$s" | python3 -c "$judge")
    g=$((g + ${v%% *}))
done
echo "tumble (six terms, noise from the scatter): GUM validated in $t of $lin seeds"
echo "gyro rate (B, K1, 20 ppm table): GUM validated in $g of $lin seeds"

cover='import json,sys
d=json.load(sys.stdin); m=d["monte_carlo"]["coefficients"]["K0"]; c=d["coefficients"]["K0"]
t=5.0
print(int(m["symmetric"][0]<=t<=m["symmetric"][1]), int(m["shortest"][0]<=t<=m["shortest"][1]),
      int(abs(c["value"]-t)<=c["U95"]), int(m["validated"]))'
for s in $(seq 1 "$ratio"); do
    $I simulate tumble --k1 1 --k0 5 --k2 0 --k3 0 --delta-o-arcsec 0 --k-ip 0 --noise 1.5 \
        --samples 4 --seed "$s" -o "$w/r.csv"
    # A recording whose K1 is not observable is refused: no result to judge.
    if out=$($I tumble --input "$w/r.csv" --mount pendulum --terms K0,K1 --json \
        --monte-carlo 4000 --seed "$s" 2>/dev/null); then
        echo "$out" | python3 -c "$cover"
    fi
done | awk -v seeds="$ratio" '{a+=$1; b+=$2; c+=$3; d+=$4; n++}
    END {printf "ratio K0 = p0/p1: %d of %d seeds reduced; coverage of the true K0: MC symmetric %.1f %%, MC shortest %.1f %%, GUM %.1f %%; GUM validated in %d\n", n, seeds, 100*a/n, 100*b/n, 100*c/n, d}'
