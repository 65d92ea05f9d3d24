"""Robot logs recorded on real vehicles, read by incal sample for sample
equal to the formats' reference readers: pyulog (PX4 ULog), rosbags
(ROS 1 bag) and mcap with mcap-ros2-support (ROS 2 MCAP, CDR). The files
and their licenses: crates/incal/tests/fixtures/robot_logs/README.md."""

import csv
import hashlib
import io
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import incal

ROOT = pathlib.Path(__file__).resolve().parents[3]
LOGS = ROOT / "crates" / "incal" / "tests" / "fixtures" / "robot_logs"
BAG = LOGS / "husky_rl_test1.bag"
MCAP = LOGS / "husky_rl_test1_imu_zstd.mcap"
ULOG_APPENDED = LOGS / "pyulog_sample_appended_multiple.ulg"
ULOG_SMALL = LOGS / "pyulog_sample_log_small.ulg"
G0 = 9.80665
DEG = 180.0 / math.pi


def incal_bin():
    return os.environ.get("INCAL_BIN", "incal")


def convert(path, *args):
    """`incal convert`'s CSV: the preamble as a dict, the columns as arrays."""
    out = subprocess.run(
        [incal_bin(), "convert", "--input", str(path), *args],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    rows = list(csv.reader(io.StringIO(out)))
    at = next(k for k, r in enumerate(rows) if r and r[0] == "time_s")
    preamble = {}
    for r in rows[:at]:
        preamble.setdefault(r[0], []).append(r[1])
    header = rows[at]
    data = np.array([[float(c) for c in r] for r in rows[at + 1 :]])
    return preamble, {h: data[:, k] for k, h in enumerate(header)}


def seconds(ns):
    ns = np.asarray(ns, dtype=np.int64)
    return (ns - ns[0]) / 1e9


def test_ulog_sensor_combined_equals_pyulog():
    pyulog = pytest.importorskip("pyulog")
    ref = pyulog.ULog(str(ULOG_APPENDED), ["sensor_combined"]).get_dataset("sensor_combined")
    pre, got = convert(ULOG_APPENDED, "--topic", "sensor_combined")
    d = ref.data
    assert len(got["time_s"]) == len(d["timestamp"]) == 2373
    np.testing.assert_allclose(got["time_s"], seconds(d["timestamp"] * 1000), rtol=0, atol=1e-9)
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(got[f"gyr_{axis}"], d[f"gyro_rad[{k}]"].astype(float) * DEG, rtol=1e-15)
        np.testing.assert_allclose(
            got[f"acc_{axis}"], d[f"accelerometer_m_s2[{k}]"].astype(float) / G0, rtol=1e-15
        )
    assert pre["format"] == ["PX4 ULog"]
    assert pre["first_stamp_s"] == [f"{d['timestamp'][0] / 1e6:.6f}".rstrip("0").rstrip(".")]


@pytest.mark.parametrize("topic,instance", [("sensor_gyro", 2), ("sensor_accel", 1), ("vehicle_imu", 1)])
def test_ulog_instances_equal_pyulog(topic, instance):
    pyulog = pytest.importorskip("pyulog")
    ulog = pyulog.ULog(str(ULOG_SMALL), [topic])
    ref = next(x for x in ulog.data_list if x.name == topic and x.multi_id == instance).data
    _, got = convert(ULOG_SMALL, "--topic", f"{topic}:{instance}")
    stamp = ref["timestamp_sample"] if "timestamp_sample" in ref else ref["timestamp"]
    np.testing.assert_allclose(got["time_s"], seconds(stamp.astype(np.int64) * 1000), atol=1e-9)
    for k, axis in enumerate("xyz"):
        if topic == "sensor_gyro":
            want = {"gyr": ref[axis].astype(float) * DEG}
        elif topic == "sensor_accel":
            want = {"acc": ref[axis].astype(float) / G0}
        else:
            want = {
                "gyr": ref[f"delta_angle[{k}]"].astype(float) / (ref["delta_angle_dt"] * 1e-6) * DEG,
                "acc": ref[f"delta_velocity[{k}]"].astype(float) / (ref["delta_velocity_dt"] * 1e-6) / G0,
            }
        for name, w in want.items():
            np.testing.assert_allclose(got[f"{name}_{axis}"], w, rtol=1e-14)
    if topic != "vehicle_imu":
        np.testing.assert_allclose(got["temperature_c"], ref["temperature"].astype(float), rtol=1e-15)


def imu_rows(msgs):
    """(stamp ns, log ns, gyro rad/s, acc m/s2) of deserialised Imu messages."""
    t, log, w, a = [], [], [], []
    for stamp, m in msgs:
        t.append(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec)
        log.append(stamp)
        w.append([m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z])
        a.append([m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z])
    return np.array(t), np.array(log), np.array(w), np.array(a)


def check_imu(got, t, w, a):
    assert len(got["time_s"]) == len(t)
    np.testing.assert_allclose(got["time_s"], seconds(t), rtol=0, atol=1e-9)
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(got[f"gyr_{axis}"], w[:, k] * DEG, rtol=1e-15)
        np.testing.assert_allclose(got[f"acc_{axis}"], a[:, k] / G0, rtol=1e-15)


def test_bag_equals_rosbags():
    rb = pytest.importorskip("rosbags.highlevel")
    with rb.AnyReader([BAG]) as reader:
        conns = [c for c in reader.connections if c.topic == "/imu/data"]
        msgs = [(ts, reader.deserialize(raw, c.msgtype)) for c, ts, raw in reader.messages(connections=conns)]
    t, log, w, a = imu_rows(msgs)
    assert len(t) == 11865
    _, got = convert(BAG)  # the bag's only sensor_msgs/Imu topic
    check_imu(got, t, w, a)
    _, by_log = convert(BAG, "--topic", "/imu/data", "--stamps", "log")
    np.testing.assert_allclose(by_log["time_s"], seconds(log), rtol=0, atol=1e-9)


def test_mcap_equals_mcap_ros2_and_the_bag():
    reader = pytest.importorskip("mcap_ros2.reader")
    msgs = [(m.log_time_ns, m.ros_msg) for m in reader.read_ros2_messages(str(MCAP), topics=["/imu/data"])]
    t, _, w, a = imu_rows(msgs)
    pre, got = convert(MCAP, "--topic", "/imu/data")
    check_imu(got, t, w, a)
    assert pre["topic"] == ["/imu/data (sensor_msgs/msg/Imu)"]
    _, bag = convert(BAG)
    for name in got:
        np.testing.assert_array_equal(got[name], bag[name])


def test_a_reduction_reads_a_log_through_python():
    doc = incal.noise(str(BAG), topic="/imu/data", columns=["gyr_z"], quantity="gyro").document
    assert doc["inputs"][0]["sha256"] == hashlib.sha256(BAG.read_bytes()).hexdigest()
    assert doc["inputs"][0]["rows"] == 11865
    assert any(p["key"] == "topic" and p["value"].startswith("/imu/data") for p in doc["preamble"])
    with pytest.raises(incal.InputError, match="topic '/nope': not in this ROS 1 bag"):
        incal.noise(str(BAG), topic="/nope")
