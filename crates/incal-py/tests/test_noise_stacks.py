"""The noise terms as VINS's, ORB-SLAM3's, OpenVINS's and Basalt's
settings from Python: each read back against the results' coefficients."""

import json
import math

import pytest

import incal


@pytest.fixture(scope="module")
def results():
    g, _ = incal.simulate.noise(quantity="gyro", rate_hz=100, duration_s=3600, arw_deg_rth=0.2, rrw_deg_h_rth=40, channels=3, seed=11)
    a, _ = incal.simulate.noise(quantity="accel", rate_hz=100, duration_s=3600, vrw_ug_rthz=60, accel_rw_ug_rts=30, channels=3, seed=11)
    return incal.noise(g, quantity="gyro"), incal.noise(a, quantity="accel")


def _values(text):
    out = {}
    for line in text.splitlines():
        s = line.strip()
        if not s or s.startswith("#") or s.startswith("%") or ":" not in s:
            continue
        k, v = s.split(":", 1)
        v = v.split("#")[0].strip()
        if v:
            out[k.strip()] = v
    return out


def _largest(r, term, si):
    return max(r.coefficients[f"ch{i}.{term}"].value for i in (1, 2, 3)) * si


def test_each_stack_reads_back(results, tmp_path):
    g, a = results
    rad = math.pi / 180
    gn, gw = _largest(g, "ARW", rad / 60), _largest(g, "RRW", rad / 216000)
    an = _largest(a, "VRW", 1e-6 * 9.80665)
    v = _values(incal.export_vins(g, a, inflate=2.0))
    assert math.isclose(float(v["gyr_n"]), 2 * gn * math.sqrt(200), rel_tol=1e-9)
    assert math.isclose(float(v["gyr_w"]), 2 * gw * math.sqrt(100), rel_tol=1e-9)
    v = _values(incal.export_orbslam3(g, a, rate_hz=200))
    assert math.isclose(float(v["IMU.NoiseAcc"]), an, rel_tol=1e-9)
    assert float(v["IMU.Frequency"]) == 200
    path = tmp_path / "imu_chain.yaml"
    v = _values(incal.export_openvins(g, a, str(path), topic="/imu"))
    assert v["rostopic"] == "/imu" and path.read_text().startswith("%YAML:1.0")
    b = json.loads(incal.export_basalt(g, a))["value0"]
    assert len(b["gyro_noise_std"]) == 3
    assert math.isclose(max(b["gyro_noise_std"]), gn, rel_tol=1e-9)
    with pytest.raises(incal.InputError, match="inflate"):
        incal.export_vins(g, a, inflate=0.1)
