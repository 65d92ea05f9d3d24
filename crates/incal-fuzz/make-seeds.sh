#!/bin/sh
# Regenerate the fuzz seeds (one valid input per target) with the incal
# simulators: INCAL=target/debug/incal sh crates/incal-fuzz/make-seeds.sh
# The seeds are small on purpose: a fuzzer mutates them byte by byte.
# gfimu-geometry (the paper layout) and limits are written by hand.
set -eu
INCAL=${INCAL:-target/debug/incal}
D=$(dirname "$0")/seeds
mkdir -p "$D"
$INCAL simulate tumble --samples 3 --seed 3 -o "$D/tumble"
$INCAL simulate centrifuge --levels-g 0,1,4,9 --samples 3 -o "$D/centrifuge"
$INCAL simulate misalign gyro --records 1 -o "$D/misalign-gyro"
$INCAL simulate misalign gyro --time-series --configs 0:0,0:180,180:180,90:180,0:90 --rates-deg-s 20,40 --records 1 --samples-per-turn 12 -o "$D/misalign-gyro-raw"
$INCAL simulate misalign accel --samples 3 -o "$D/misalign-accel"
$INCAL simulate gfimu --seed 3 -o "$D/gfimu-calibrate"
$INCAL simulate gfimu --kind motion --duration-s 0.2 --seed 3 -o "$D/gfimu-solve"
$INCAL gfimu calibrate --input "$D/gfimu-calibrate" --json -o "$D/gfimu-calibration"
$INCAL simulate gyro-rate --samples 4 -o "$D/gyro-rate"
$INCAL simulate gyro-positions --samples 4 -o "$D/gyro-positions"
$INCAL simulate noise --duration-s 20 --rate-hz 100 --seed 3 -o "$D/noise"
$INCAL simulate imu --sequence ferraris --static-s 0.5 --rotation-s 1 -o "$D/imu-ferraris"
$INCAL simulate imu --sequence positions --static-s 0.3 -o "$D/imu-multipos"
$INCAL simulate imu --sequence random --orientations 12 --init-static-s 3 --static-s 2 --move-s 1.5 -o "$D/imu-autocal"
$INCAL imu ferraris --input "$D/imu-ferraris" --rate-hz 100 --json -o "$D/imu-calibration"
$INCAL tumble --mount pendulum --input "$D/tumble" --json -o "$D/result"
$INCAL simulate response-sine --dwells-hz 2,5,10,20,40 --seconds-per-dwell 0.1 --min-cycles 3 --rate-hz 200 --corner-hz 20 --order first --delay-s 0.005 --seed 3 -o "$D/response-sine"
$INCAL simulate response-broadband --duration-s 0.6 --seed 3 -o "$D/response-broadband"
$INCAL simulate response-step --duration-s 0.2 --step-s 0.05 --rate-hz 500 --corner-hz 40 --seed 3 -o "$D/response-step"
$INCAL simulate warmup --duration-s 240 --rate-hz 1 --tau-s 40 --seed 3 -o "$D/warmup"
$INCAL simulate threshold --dwell-s 2 --rate-hz 5 --seed 3 -o "$D/threshold"
$INCAL simulate mag --orientations 12 --dwell-s 0.2 --move-s 0.1 --rate-hz 20 --seed 3 -o "$D/mag"
$INCAL simulate sensitivity --levels 0,4,8 --run-s 1 --gap-s 0.5 --rate-hz 20 --seed 3 -o "$D/sensitivity"
$INCAL simulate repeatability --seed 3 -o "$D/repeatability"
$INCAL simulate thermal --seed 3 --t-low-c 20 --t-high-c 40 --ramp-c-per-min 20 --hold-s 30 --lag-s 5 --rate-hz 1 -o "$D/thermal-ramp"
$INCAL tumble --mount pendulum --input "$D/tumble" --json --meta temperature_c=25 -o "$D/thermal-fit"
$INCAL thermal ramp --input "$D/thermal-ramp" --rate-hz 1 --quantity gyro --json -o "$D/thermal-model"
# ulog, ros-bag and mcap: make-robot-seeds.py (Python, rosbags and
# mcap-ros2-support). lab-profile is written by hand; record-import is the export of a store
# holding the result seed.
STORE=$(mktemp -d)/seed.db
$INCAL record add "$D/result" --serial SN-1 --db "$STORE" --created-utc 2026-01-01T00:00:00Z > /dev/null
$INCAL record export --db "$STORE" -o "$D/record-import"
rm -rf "$(dirname "$STORE")"
