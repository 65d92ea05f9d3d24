"""Recordings as loggers write them: a preamble before the header is read
past and recorded (``header_line`` names the header), its stated rate is
used, and ``rate_hz`` is optional wherever ``time_s`` gives the times."""

import numpy as np
import pytest

import incal


def logger_file(tmp_path):
    """A 60 s, 100 Hz white-noise record after an MPU-6050 logger's
    preamble, without ``time_s``; and the samples."""
    rng = np.random.default_rng(3)
    x = 0.01 * rng.standard_normal(6000)
    lines = ["Device,MPU6050", "Fs,100", "Logging Type,0", "gx"] + [repr(float(v)) for v in x]
    path = tmp_path / "log.csv"
    path.write_text("\n".join(lines) + "\n")
    return path, x


def test_a_preamble_is_recorded_and_its_rate_used(tmp_path):
    path, x = logger_file(tmp_path)
    r = incal.noise(str(path), deviations="oadev")
    assert r.document["options"]["rate_hz"] == 100.0
    assert [(p["line"], p["key"], p["value"]) for p in r.document["preamble"]] == [
        (1, "Device", "MPU6050"),
        (2, "Fs", "100"),
        (3, "Logging Type", "0"),
    ]
    # The same samples in memory, at the rate given: the same numbers.
    m = incal.noise(x, rate_hz=100, deviations="oadev")
    n = r.coefficients["gx.N"]
    assert n.value == pytest.approx(m.coefficients[next(k for k in m.coefficients if k.endswith(".N"))].value, rel=1e-12)
    named = incal.noise(str(path), header_line=4, deviations="oadev")
    assert named.coefficients["gx.N"].value == n.value
    with pytest.raises(incal.InputError, match="preamble states a sample rate of 100 Hz"):
        incal.noise(str(path), rate_hz=200)
    with pytest.raises(incal.InputError, match="header_line"):
        incal.noise(str(path), header_line="first")


def test_the_stamps_give_the_autocalibration_its_rate(tmp_path):
    data, _ = incal.simulate.imu(
        sequence="random", orientations=14, init_static_s=3, static_s=2, move_s=1.5, seed=5
    )
    given = incal.imu_autocal(data, rate_hz=100, init_static_s=3)
    stamped = incal.imu_autocal(data, init_static_s=3)
    assert stamped.document["options"]["rate_hz"] == pytest.approx(100.0, rel=1e-9)
    for k, c in given.coefficients.items():
        assert stamped.coefficients[k].value == pytest.approx(c.value, rel=1e-9, abs=1e-12)


def test_a_rig_log_is_segmented_as_the_cli_does(tmp_path):
    """A dividing head's log (encoder jitter, moves, settling with the
    output off): segmented with the plan's angles it gives the labelled
    rows' coefficients exactly."""
    labelled, _ = incal.simulate.tumble(samples=30, noise=3e-4, seed=4)
    angles = labelled["angle_deg"].to_numpy()
    out = labelled["output"].to_numpy()
    rng = np.random.default_rng(1)
    rows, plan = [], []
    starts = [0] + [i for i in range(1, len(angles)) if angles[i] != angles[i - 1]] + [len(angles)]
    for a, b in zip(starts, starts[1:]):
        v = float(angles[a])
        plan.append(v)
        # 1 s moving, 1 s settling (output off by 1), then the labelled rows.
        moving = [(v + 5.0 * (m + 1), 9.0) for m in range(10)]
        settling = [(v + 5e-4 * rng.uniform(-1, 1), float(out[a]) + 1.0) for _ in range(10)]
        at_rest = [(v + 5e-4 * rng.uniform(-1, 1), float(out[i])) for i in range(a, b)]
        for x, y in moving + settling + at_rest:
            rows.append((len(rows) * 0.1, x, y))
    log = tmp_path / "head.csv"
    log.write_text("time_s,angle_deg,output\n" + "".join(f"{t!r},{x!r},{y!r}\n" for t, x, y in rows))
    got = incal.tumble(
        str(log), mount="pendulum", segment_by="angle_deg", segment_settle_s=1, segment_values=plan
    )
    want = incal.tumble(labelled, mount="pendulum")
    for name, c in want.coefficients.items():
        assert got.coefficients[name].value == pytest.approx(c.value, rel=1e-12, abs=1e-15)
    segs = got.table("segments")
    assert len(segs) == len(plan)
    assert got.document["segmentation"]["column"] == "angle_deg"
    with pytest.raises(incal.InputError, match="segment_tolerance"):
        incal.tumble(str(log), mount="pendulum", segment_by="angle_deg", segment_tolerance="wide")


def test_clipped_samples_are_named(tmp_path):
    """A 16-bit channel pinned at -32768 for 16 rows is named with its
    lines; with ``full_scale`` a run at it is too."""
    rows = ["time_s,gx"]
    for k in range(2000):
        v = -32768 if 100 <= k <= 115 else (30 if 800 <= k <= 803 else (k * 7919) % 61 - 30)
        rows.append(f"{k / 100!r},{v}")
    path = tmp_path / "counts.csv"
    path.write_text("\n".join(rows) + "\n")
    r = incal.noise(str(path), deviations="oadev")
    clipped = [w["message"] for w in r.document["warnings"] if w["code"] == "clipped"]
    assert clipped == [
        "gx sits at the rail -32768 in 16 samples (1 run: lines 102-117): "
        "clipped, they are not what the sensor sensed"
    ]
    r = incal.noise(str(path), deviations="oadev", full_scale=29.5)
    # Beyond a full scale the run is at the rail of its sign, +29.5.
    assert any("rail 29.5 in 4 samples" in w["message"] for w in r.document["warnings"])
