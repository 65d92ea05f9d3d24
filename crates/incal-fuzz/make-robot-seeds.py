"""Write the robot-log fuzz seeds (`ulog`, `ros-bag`, `mcap`): four seconds
of a still IMU at 100 Hz (the noise target's rate), white noise from a
fixed seed, as PX4's `sensor_gyro` (ULog, written here byte by byte), a
ROS 1 bag and a ROS 2 MCAP of `sensor_msgs/Imu` (rosbags and
mcap-ros2-support: `pip install numpy rosbags mcap-ros2-support`).

    python3 crates/incal-fuzz/make-robot-seeds.py crates/incal-fuzz/seeds
"""

import struct
import sys
from pathlib import Path

import numpy as np

N, RATE = 400, 100.0
out = Path(sys.argv[1] if len(sys.argv) > 1 else "crates/incal-fuzz/seeds")
rng = np.random.default_rng(3)
gyro = rng.normal(0.0, 0.002, (N, 3))  # rad/s
acc = rng.normal(0.0, 0.02, (N, 3)) + [0.0, 0.0, -9.80665]  # m/s2


def ulog() -> bytes:
    def msg(kind: bytes, body: bytes) -> bytes:
        return struct.pack("<H", len(body)) + kind + body

    b = b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0)
    b += msg(b"F", b"sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;uint8_t[4] _padding0;")
    b += msg(b"A", b"\x00" + struct.pack("<H", 1) + b"sensor_gyro")
    for k in range(N):
        t = 1_000_000 + k * 10_000
        body = struct.pack("<HQQI4fI3sB4s", 1, t + 120, t, 7, *gyro[k], 40.0 + 0.001 * k, 0, b"\0\0\0", 1, b"\0" * 4)
        b += msg(b"D", body)
    return b


def imu_messages(typestore, ros1: bool):
    Imu = typestore.types["sensor_msgs/msg/Imu"]
    Header = typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    Quaternion = typestore.types["geometry_msgs/msg/Quaternion"]
    Vector3 = typestore.types["geometry_msgs/msg/Vector3"]
    for k in range(N):
        ns = 1_700_000_000 * 10**9 + k * 10_000_000
        yield ns, Imu(
            header=Header(**({"seq": k} if ros1 else {}), stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="imu"),
            orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=np.zeros(9),
            angular_velocity=Vector3(x=gyro[k, 0], y=gyro[k, 1], z=gyro[k, 2]),
            angular_velocity_covariance=np.zeros(9),
            linear_acceleration=Vector3(x=acc[k, 0], y=acc[k, 1], z=acc[k, 2]),
            linear_acceleration_covariance=np.zeros(9),
        )


def bag(path: Path) -> None:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    path.unlink(missing_ok=True)
    with Writer(path) as w:
        conn = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        for ns, m in imu_messages(store, True):
            w.write(conn, ns + 2_000_000, store.serialize_ros1(m, "sensor_msgs/msg/Imu"))


def mcap(path: Path) -> None:
    from mcap_ros2.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    schema_text = (
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
        "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
        "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"
        "================================================================================\nMSG: std_msgs/Header\n"
        "builtin_interfaces/Time stamp\nstring frame_id\n"
        "================================================================================\nMSG: builtin_interfaces/Time\n"
        "int32 sec\nuint32 nanosec\n"
        "================================================================================\nMSG: geometry_msgs/Quaternion\n"
        "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n"
        "================================================================================\nMSG: geometry_msgs/Vector3\n"
        "float64 x\nfloat64 y\nfloat64 z\n"
    )
    with open(path, "wb") as f:
        w = Writer(f, compression=None)
        schema = w.register_msgdef("sensor_msgs/msg/Imu", schema_text)
        for ns, m in imu_messages(store, False):
            raw = {
                "header": {"stamp": {"sec": m.header.stamp.sec, "nanosec": m.header.stamp.nanosec}, "frame_id": "imu"},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                "orientation_covariance": [0.0] * 9,
                "angular_velocity": {"x": m.angular_velocity.x, "y": m.angular_velocity.y, "z": m.angular_velocity.z},
                "angular_velocity_covariance": [0.0] * 9,
                "linear_acceleration": {"x": m.linear_acceleration.x, "y": m.linear_acceleration.y, "z": m.linear_acceleration.z},
                "linear_acceleration_covariance": [0.0] * 9,
            }
            w.write_message("/imu", schema, raw, log_time=ns + 2_000_000, publish_time=ns)
        w.finish()


(out / "ulog").write_bytes(ulog())
bag(out / "ros-bag")
mcap(out / "mcap")
