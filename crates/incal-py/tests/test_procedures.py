"""Every procedure from Python equals the CLI: for the same file and
options, ``incal.<procedure>(path, **options).document`` is the ``incal
... --json`` document, and the same data as a DataFrame or as arrays gives
identical coefficients."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import incal

ROOT = pathlib.Path(__file__).resolve().parents[3]
BIN = os.environ.get("INCAL_BIN", str(ROOT / "target" / "debug" / "incal"))

def _kwargs(args):
    """CLI options (``--mount pendulum``) as Python keywords (``mount="pendulum"``)."""
    out, i = {}, 0
    while i < len(args):
        key = args[i][2:].replace("-", "_")
        if i + 1 < len(args) and not args[i + 1].startswith("--"):
            out[key], i = args[i + 1], i + 2
        else:
            out[key], i = True, i + 1
    return out


# (function, CLI words, simulate words, options): every procedure that
# reduces a simulated recording, with its worked example from the
# procedure registry (``incal procedures --json``).
CASES = [
    (
        e["python"]["function"],
        e["command"].split(),
        e["simulate"].split()[1:] + e["example"]["simulate"],
        _kwargs(e["example"]["options"]),
    )
    for e in incal.REGISTRY
    if e["example"]
]


def flags(options):
    """Keywords as the CLI's options (``name_x=v`` is ``--name-x v``; a
    flag alone for ``True``; a list joined by commas), to run the same
    call through the binary."""
    out = []
    for key, value in options.items():
        if value is None or value is False:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            out.append(flag)
        elif isinstance(value, (list, tuple)):
            out += [flag, ",".join(repr(v) if isinstance(v, float) else str(v) for v in value)]
        else:
            out += [flag, repr(value) if isinstance(value, float) else str(value)]
    return out


def cli(words):
    r = subprocess.run([BIN] + [str(w) for w in words], capture_output=True)
    assert r.returncode == 0, r.stderr.decode()
    return r.stdout


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    d = tmp_path_factory.mktemp("recordings")
    out = {}
    for name, _, sim, _ in CASES:
        p = d / f"{name}.csv"
        cli(["simulate"] + sim + ["-o", p])
        out[name] = p
    return out


@pytest.mark.parametrize("name,words,sim,options", CASES, ids=[c[0] for c in CASES])
def test_document_equals_the_cli_json(recordings, name, words, sim, options):
    path = recordings[name]
    result = getattr(incal, name)(str(path), **options)
    expected = json.loads(cli(words + ["--input", path, "--json"] + flags(options)))
    assert result.document == expected
    assert result.procedure == expected["procedure"]
    # Written back, the document is the CLI's file byte for byte.
    assert result.to_json() == cli(words + ["--input", path, "--json"] + flags(options)).decode()


@pytest.mark.parametrize("name,words,sim,options", CASES, ids=[c[0] for c in CASES])
def test_dataframe_and_arrays_give_the_same_coefficients(recordings, name, words, sim, options):
    import pandas as pd

    path = recordings[name]
    from_file = getattr(incal, name)(str(path), **options).coefficients
    frame = incal._read_csv(path.read_bytes())
    assert getattr(incal, name)(frame, **options).coefficients == from_file
    arrays = {c: frame[c].to_numpy() for c in frame.columns}
    assert getattr(incal, name)(**arrays, **options).coefficients == from_file


def _but_inputs(doc):
    return {k: v for k, v in doc.items() if k != "inputs"}


@pytest.mark.parametrize("name,words,sim,options", CASES, ids=[c[0] for c in CASES])
def test_a_dataframe_gives_the_cli_document_with_its_own_input(recordings, name, words, sim, options):
    """Data in memory: the whole document is the CLI's, but for the input
    it names (``<DataFrame>``, the hash of the columns' canonical form,
    the same rows)."""
    path = recordings[name]
    expected = json.loads(cli(words + ["--input", path, "--json"] + flags(options)))
    frame = incal._read_csv(path.read_bytes())
    got = getattr(incal, name)(frame, **options).document
    assert _but_inputs(got) == _but_inputs(expected)
    (i,) = [x for x in got["inputs"] if x["role"] == "input"]
    assert i["path"] in ("<DataFrame>", "<memory>") and i["rows"] == len(frame)
    again = getattr(incal, name)(frame.copy(), **options).document
    assert again["inputs"] == got["inputs"], "the same columns give the same hash"


@pytest.mark.parametrize("name,words,sim,options", CASES, ids=[c[0] for c in CASES])
def test_a_simulator_gives_the_cli_recording(name, words, sim, options):
    entry = next(e for e in incal.REGISTRY if e["python"]["function"] == name)
    simulate = getattr(incal.simulate, entry["python"]["simulate"])
    frame, notes = simulate(**_kwargs(entry["example"]["simulate"]))
    expected = incal._read_csv(cli(["simulate"] + sim + ["-o", "-"]))
    assert frame.equals(expected)


@pytest.mark.parametrize(
    "name,words",
    [
        ("tumble", ["--k1", "10", "--noise", "1e-6", "--samples", "10"]),
        ("gyro_rate", ["--rates-deg-s", "-10,10,50", "--noise", "1e-3", "--k1", "1"]),
        ("imu_ferraris", ["--seeds", "2"]),
        ("noise", ["--seeds", "2", "--duration-s", "300", "--rate-hz", "10", "--seed", "3"]),
    ],
)
def test_a_plan_is_the_cli_plan(name, words):
    got = getattr(incal.plan, name)(**_kwargs(words))
    cli_name = next(e["plan"] for e in incal.REGISTRY if e["python"]["plan"] == name).split()[1:]
    assert got == json.loads(cli(["plan"] + cli_name + words + ["--json"]))


def test_errors_are_exceptions_with_the_cli_message(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("angle_deg,output\n0,0.11\n30,abc\n")
    with pytest.raises(incal.InputError) as e:
        incal.tumble(str(bad), mount="pendulum")
    assert str(e.value) == f"{bad}:3: column 'output': 'abc' is not a number"
    assert isinstance(e.value, ValueError) and e.value.code == 2
    assert (e.value.file, e.value.line, e.value.column, e.value.option) == (str(bad), 3, "output", None)
    with pytest.raises(incal.InputError) as e:
        incal.tumble(str(bad), mount="pendulum", noise=-1)
    assert e.value.option == "noise" and e.value.file is None
    missing = tmp_path / "missing.csv"
    missing.write_text("angle_deg,outpt\n0,1\n")
    with pytest.raises(incal.InputError) as e:
        incal.tumble(str(missing), mount="pendulum")
    assert (e.value.file, e.value.line, e.value.column) == (str(missing), None, "output")
    # A misspelt keyword is a TypeError at the call, as for any function;
    # the command line's unknown option names it too.
    with pytest.raises(TypeError, match="no_such_option_hz"):
        incal.tumble(str(bad), mount="pendulum", no_such_option_hz=1)
    with pytest.raises(incal.InputError) as e:
        incal.run(["tumble", "--input", str(bad), "--no-such-option-hz", "1"])
    assert e.value.option == "no_such_option_hz"
    with pytest.raises(incal.InputError, match="sideways.*pendulum.*gate") as e:
        incal.tumble(str(bad), mount="sideways")
    assert e.value.option == "mount"
    with pytest.raises(incal.InputError, match="no data"):
        incal.tumble(mount="pendulum")


def test_plans_simulators_compare_report_and_apply(tmp_path):
    plan = incal.plan.tumble(k1=10, noise=1e-6)
    assert plan["schema"] == "incal.plan/1" and plan["predicted_u"]["K1"] > 0
    data, notes = incal.simulate.tumble(seed=7)
    assert list(data.columns) == ["angle_deg", "output"] and len(data) > 0
    a = incal.tumble(data, mount="pendulum")
    b_path = tmp_path / "b.json"
    incal.tumble(incal.simulate.tumble(seed=8)[0], mount="pendulum").to_json(str(b_path))
    c = incal.compare(a, str(b_path))
    assert "K1" in json.dumps(c)
    html = a.report(str(tmp_path / "a.html"))
    assert pathlib.Path(html).read_text().startswith("<!DOCTYPE html>")
    assert "<table>" in a._repr_html_()
    assert incal.read_result(str(b_path)).coefficients.keys() == a.coefficients.keys()
    raw, _ = incal.simulate.imu(sequence="ferraris", static_s=0.5, rotation_s=1)
    cal = incal.imu_ferraris(raw, rate_hz=100)
    cal_path = tmp_path / "cal.json"
    cal.to_json(str(cal_path))
    out = incal.apply(str(cal_path), raw)
    assert len(out) == len(raw) and np.isfinite(out.select_dtypes("number").to_numpy()).all()
    # Columns apply does not calibrate (the section label) are carried through.
    assert "part" in out.columns and list(out["part"]) == list(raw["part"])


def test_the_worked_example_runs(tmp_path):
    example = ROOT / "crates" / "incal-py" / "examples" / "tumble_in_python.py"
    r = subprocess.run(
        [os.sys.executable, str(example), str(tmp_path)], capture_output=True, text=True
    )
    assert r.returncode == 0, r.stderr
    assert "verdict: pass" in r.stdout
    assert (tmp_path / "t.html").exists()


@pytest.mark.parametrize(
    "name,options",
    [
        ("imu_ferraris", {"rate_hz": 100}),
        ("imu_multipos", {"rate_hz": 100}),
        ("imu_autocal", {"rate_hz": 100, "init_static_s": 3}),
    ],
)
def test_imu_calibrations_load_in_imucal_and_calibrate_as_incal_does(recordings, tmp_path, name, options):
    from imucal.management import load_calibration_info

    raw = incal._read_csv(recordings[name].read_bytes())
    result = getattr(incal, name)(raw, **options)
    path = tmp_path / "cal.json"
    exported = result.to_imucal(str(path))
    cal = load_calibration_info(path)
    assert type(cal).__name__ == "FerrarisCalibrationInfo"
    assert exported["cal_type"] == "Ferraris"
    acc = raw[["acc_x", "acc_y", "acc_z"]].to_numpy()
    gyr = raw[["gyr_x", "gyr_y", "gyr_z"]].to_numpy()
    acc_i, gyr_i = cal.calibrate(acc, gyr, "a.u.", "a.u.")
    result.to_json(str(tmp_path / "r.json"))
    ours = incal.apply(str(tmp_path / "r.json"), raw)
    acc_o = ours[[c for c in ours.columns if c.startswith("acc_")]].to_numpy()
    gyr_o = ours[[c for c in ours.columns if c.startswith("gyr_")]].to_numpy()
    if name == "imu_autocal":
        gyr_o = np.degrees(gyr_o)
    np.testing.assert_allclose(acc_i, acc_o, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(gyr_i, gyr_o, rtol=1e-9, atol=1e-9)


def test_the_package_ships_its_type_stubs():
    pkg = pathlib.Path(incal.__file__).parent
    for stub in ["__init__.pyi", "plan.pyi", "simulate.pyi", "batch.pyi", "records.pyi", "warnings.pyi", "py.typed"]:
        assert (pkg / stub).exists(), stub
    text = (pkg / "__init__.pyi").read_text()
    for name in incal.__all__:
        if name not in ("plan", "simulate", "batch", "Records", "IncalWarning"):
            assert f"def {name}(" in text or f"class {name}" in text, name
    assert "from .records import Records as Records" in text
    for module, stub in [(incal.batch, "batch.pyi"), (incal.records, "records.pyi")]:
        text = (pkg / stub).read_text()
        for name in module.__all__:
            assert f"def {name}(" in text or f"class {name}" in text or f"{name}:" in text, (stub, name)


def test_noise_reads_numpy_arrays_in_place(tmp_path):
    """A float64 array is the binary record itself (no copy, no text): the
    same numbers and the same input hash as the file of its bytes; f32,
    strided and several channels give what their files give."""
    rng = np.random.default_rng(5)
    x = rng.normal(0.0, 0.01, 200_000)
    y = rng.normal(0.0, 0.02, 200_000).astype(np.float32)
    x.astype("<f8").tofile(tmp_path / "x.bin")
    from_array = incal.noise(gx=x, rate_hz=100)
    from_file = incal.noise(tmp_path / "x.bin", format="f64le", channels=1, rate_hz=100, columns="gx=ch1")
    assert from_array.coefficients == from_file.coefficients
    assert from_array.document["inputs"][0]["path"] == "<memory>"
    assert from_array.document["inputs"][0]["sha256"] == from_file.document["inputs"][0]["sha256"]
    # float32 stays float32; a strided view is made contiguous first.
    y.tofile(tmp_path / "y.bin")
    assert incal.noise(gy=y, rate_hz=100).coefficients == incal.noise(
        tmp_path / "y.bin", format="f32le", channels=1, rate_hz=100, columns="gy=ch1").coefficients
    strided = x[::2]
    np.ascontiguousarray(strided).tofile(tmp_path / "s.bin")
    assert incal.noise(gx=strided, rate_hz=50).coefficients == incal.noise(
        tmp_path / "s.bin", format="f64le", channels=1, rate_hz=50, columns="gx=ch1").coefficients
    # Two channels: interleaved as the two-channel file.
    np.column_stack([x, y.astype(np.float64)]).tofile(tmp_path / "xy.bin")
    both = incal.noise(gx=x, gy=y.astype(np.float64), rate_hz=100)
    assert both.coefficients == incal.noise(
        tmp_path / "xy.bin", format="f64le", channels=2, rate_hz=100, columns="gx=ch1,gy=ch2").coefficients
    with pytest.raises(incal.InputError, match="column 'gy' has 3 values"):
        incal.noise(gx=x, gy=np.zeros(3), rate_hz=100)


def test_noise_takes_an_array_positionally_as_allantools_does(tmp_path):
    """``incal.noise(y, rate_hz=...)``: a 1-D array is channel ``ch1``, a
    2-D array one channel per column, read in place as by keyword."""
    rng = np.random.default_rng(8)
    x = rng.normal(0.0, 0.01, 50_000)
    y = rng.normal(0.0, 0.02, 50_000)
    one = incal.noise(x, rate_hz=100)
    assert one.coefficients == incal.noise(ch1=x, rate_hz=100).coefficients
    assert one.document["inputs"][0]["path"] == "<memory>"
    two = incal.noise(np.column_stack([x, y]), rate_hz=100)
    assert two.coefficients == incal.noise(ch1=x, ch2=y, rate_hz=100).coefficients
    with pytest.raises(incal.InputError, match="3 dimensions"):
        incal.noise(np.zeros((2, 2, 2)), rate_hz=100)
    with pytest.raises(incal.InputError, match="given twice"):
        incal.noise(x, ch1=y, rate_hz=100)


def test_kalibr_yaml_reads_back_in_pyyaml(tmp_path):
    """Kalibr reads imu.yaml with PyYAML: every value comes back as a float
    equal to the largest axis's term converted to SI continuous time."""
    import math

    import yaml

    def sim(name, *args):
        p = tmp_path / name
        incal.run(["simulate", "noise", "--rate-hz", "100", "--duration-s", "3600", "--channels", "3",
                   "--seed", "11", "-o", p, *args])
        return p

    g = incal.noise(sim("g.csv", "--quantity", "gyro", "--arw-deg-rth", "0.2", "--rrw-deg-h-rth", "40"),
                    rate_hz=100, quantity="gyro")
    a = incal.noise(sim("a.csv", "--quantity", "accel", "--vrw-ug-rthz", "60", "--accel-rw-ug-rts", "30"),
                    rate_hz=100, quantity="accel")
    text = incal.export_kalibr(g, a, tmp_path / "imu.yaml")
    y = yaml.safe_load((tmp_path / "imu.yaml").read_text())
    assert yaml.safe_load(text) == y

    def largest(r, term):
        return max(r.coefficients[f"ch{k}.{term}"]["value"] for k in (1, 2, 3))

    want = {
        "gyroscope_noise_density": largest(g, "ARW") * math.pi / 180 / 60,
        "gyroscope_random_walk": largest(g, "RRW") * math.pi / 180 / 3600 / 60,
        "accelerometer_noise_density": largest(a, "VRW") * 1e-6 * 9.80665,
        "accelerometer_random_walk": largest(a, "acceleration_random_walk") * 1e-6 * 9.80665,
        "update_rate": 100.0,
    }
    assert set(y) == set(want)
    for k, v in want.items():
        assert isinstance(y[k], float), (k, y[k])
        assert y[k] == pytest.approx(v, rel=1e-12), k
    # PX4: the same densities times sqrt(EKF rate), in QGC's parameter file.
    params = incal.export_px4(g, a, ekf_rate_hz=250)
    rows = [ln.split("\t") for ln in params.splitlines() if not ln.startswith("#")]
    got = {r[2]: float(r[3]) for r in rows}
    for name, key in [("EKF2_GYR_NOISE", "gyroscope_noise_density"),
                      ("EKF2_ACC_NOISE", "accelerometer_noise_density"),
                      ("EKF2_GYR_B_NOISE", "gyroscope_random_walk"),
                      ("EKF2_ACC_B_NOISE", "accelerometer_random_walk")]:
        assert got[name] == pytest.approx(want[key] * math.sqrt(250), rel=1e-12), name
    white = incal.noise(sim("w.csv", "--quantity", "gyro", "--arw-deg-rth", "0.2"), rate_hz=100, quantity="gyro")
    with pytest.raises(incal.InputError, match="RRW was not identified"):
        incal.export_kalibr(white, a)
    with pytest.raises(incal.InputError, match="RRW was not identified"):
        incal.export_px4(white, a)


def test_fail_on_stops_with_the_result_kept(tmp_path):
    data, _ = incal.simulate.tumble(seed=2)
    r = incal.tumble(data, mount="pendulum")
    k0 = r.coefficients["K0"]
    limits = tmp_path / "l.toml"
    limits.write_text(f'[tumble]\nK0 = {{ max = {k0["value"] - 1e-9} }}\n')
    with pytest.raises(incal.IncalError, match="stopped by fail_on='fail'") as e:
        incal.tumble(data, mount="pendulum", limits=limits, fail_on="fail")
    assert e.value.code == 3
    assert e.value.result.document["verdict"] == "fail"
    assert e.value.result.coefficients == r.coefficients


def test_thermal_ramp_fit_apply_and_exports(tmp_path):
    data, truth = incal.simulate.thermal(seed=5, rate_hz=1, hold_s=300, ramp_c_per_min=4)
    assert list(data.columns[:3]) == ["time_s", "chamber_c", "temperature_c"]
    assert truth["lag_s"] == 120.0
    model = incal.thermal_ramp(data, rate_hz=1, quantity="gyro")
    assert model.procedure == "thermal"
    c1 = model.coefficients["gx.c1"]
    assert abs(c1["value"] - truth["channels"]["gx"]["c"][1]) < 5 * c1["u"]
    fixed = incal.thermal_apply(model, data)
    assert list(fixed.columns) == list(data.columns)
    assert len(fixed) == len(data)
    px4 = incal.export_thermal(model, "px4", device_id=3)
    assert "TC_G0_ID\t3\t6" in px4
    ap = incal.export_thermal(model, "ardupilot", imu=2, path=str(tmp_path / "t.parm"))
    assert (tmp_path / "t.parm").read_text() == ap and "INS_TCAL2_GYR1_X," in ap
    # From a path, each export is the CLI's text byte for byte.
    model_path = tmp_path / "model.json"
    model.to_json(str(model_path))
    assert incal.export_thermal(str(model_path), "px4", device_id=3, axes="gy,gx,gz") == cli(
        ["export", "px4", model_path, "--device-id", "3", "--axes", "gy,gx,gz"]
    ).decode()
    assert incal.export_thermal(str(model_path), "ardupilot", imu=2) == cli(
        ["export", "ardupilot", model_path, "--imu", "2"]
    ).decode()
    # Soak: tumble results at three temperatures, by meta.
    docs = []
    for i, t in enumerate([-10, 25, 60]):
        d, _ = incal.simulate.tumble(seed=40 + i)
        docs.append(incal.tumble(d, mount="pendulum", meta=[f"temperature_c={t}"]))
    soak = incal.thermal_fit(docs, t_ref_c=20)
    assert soak.document["thermal"]["K1"]["t_ref_c"] == 20
    paths = []
    for i, d in enumerate(docs):
        paths.append(tmp_path / f"soak{i}.json")
        d.to_json(str(paths[-1]))
    expected = json.loads(cli(["thermal", "fit"] + paths + ["--t-ref-c", "20", "--serial", "SN-9", "--json"]))
    assert incal.thermal_fit([str(p) for p in paths], t_ref_c=20, serial="SN-9").document == expected
    assert "K1.c0" in soak.coefficients
    with pytest.raises(incal.InputError, match="K0.c3"):
        incal.thermal_fit(docs, degree=3)


def test_every_registry_procedure_has_its_functions_and_stubs():
    """The procedure registry (``incal procedures --json``) names, for each
    procedure, its Python function, plan and simulator: each exists, is
    exported, and has its stub; no procedure function is missing."""
    pkg = pathlib.Path(incal.__file__).parent
    stubs = {m: (pkg / f"{m}.pyi").read_text() for m in ["__init__", "plan", "simulate"]}
    registry = json.loads(cli(["procedures", "--json"]))
    assert registry == incal.REGISTRY
    missing = []
    for e in registry:
        names = [("__init__", incal, e["python"]["function"])]
        names += [("plan", incal.plan, e["python"]["plan"]), ("simulate", incal.simulate, e["python"]["simulate"])]
        for stub, module, name in names:
            if name is None:
                continue
            if not callable(getattr(module, name, None)):
                missing.append(f"procedure {e['id']}: no incal.{'' if stub == '__init__' else stub + '.'}{name}")
            elif name not in module.__all__:
                missing.append(f"procedure {e['id']}: {name} not in the __all__ of {module.__name__}")
            if f"def {name}(" not in stubs[stub]:
                missing.append(f"procedure {e['id']}: no stub of {name} in {stub}.pyi")
        if e["input"] == "recording" and e["id"] not in incal.batch.PROCEDURES:
            missing.append(f"procedure {e['id']}: not in incal.batch.PROCEDURES")
    assert not missing, "\n".join(missing)
    assert incal.batch._function("thermal") == "thermal_ramp"


def test_document_warnings_are_python_warnings_of_their_category(tmp_path):
    import warnings

    e = next(e for e in incal.REGISTRY if e["id"] == "gyro-positions")
    path = tmp_path / "positions.csv"
    cli(["simulate"] + e["simulate"].split()[1:] + e["example"]["simulate"] + ["-o", path])
    options = _kwargs(e["example"]["options"])
    with pytest.warns(incal.IncalWarning) as caught:
        result = incal.gyro_positions(str(path), **options)
    codes = sorted(w["code"] for w in result.document["warnings"])
    assert "missing-uncertainty" in codes
    raised = sorted(w.category.code for w in caught if issubclass(w.category, incal.IncalWarning))
    assert raised == codes
    assert all(w.filename == __file__ for w in caught), "warnings point at the caller's line"
    with warnings.catch_warnings():
        warnings.filterwarnings("error", category=incal.warnings.MissingUncertainty)
        with pytest.raises(incal.warnings.MissingUncertainty, match=r"\[missing-uncertainty\]"):
            incal.gyro_positions(str(path), **options)


def test_every_warning_code_is_a_category_with_its_stub():
    schema = json.loads(cli(["schema"]))
    codes = [v["const"] for v in schema["$defs"]["WarningCode"]["oneOf"]]
    stub = (pathlib.Path(incal.__file__).parent / "warnings.pyi").read_text()
    for code in codes:
        cls = incal.warnings.category(code)
        assert cls is not incal.IncalWarning and cls.code == code and issubclass(cls, UserWarning)
        assert cls.__doc__, code
        assert f"class {cls.__name__}(IncalWarning): ..." in stub, f"warnings.pyi: add 'class {cls.__name__}(IncalWarning): ...'"
    assert incal.warnings.category("no-such-code") is incal.IncalWarning


def test_coefficients_read_as_attributes_and_tables_as_dataframes(recordings):
    r = incal.tumble(str(recordings["tumble"]), mount="pendulum")
    k1 = r.coefficients["K1"]
    assert (k1.value, k1.u, k1.U95, k1.dof, k1.unit, k1.k95) == (
        k1["value"], k1["u"], k1["U95"], k1.get("dof"), k1["unit"], k1["k95"])
    assert k1 == r.document["coefficients"]["K1"]
    positions = r.table("positions")
    t = next(t for t in r.document["tables"] if t["id"] == "positions")
    assert len(positions) == len(t["rows"]) and "angle [deg]" in positions.columns
    with pytest.raises(KeyError, match="tables: positions"):
        r.table("no-such-table")


def test_signatures_list_every_option_with_its_default_and_refuse_a_misspelt_one(recordings):
    import inspect

    sig = inspect.signature(incal.gyro_rate)
    params = sig.parameters
    assert list(params)[0] == "data"
    assert params["latitude_deg"].default is inspect.Parameter.empty  # required
    assert params["ia"].default == "up"
    assert params["rate_uncertainty_ppm"].default == 0
    assert params["serial"].default is None and "json" not in params and "input" not in params
    assert "deg" in incal.gyro_rate.__doc__ and "latitude_deg (required)" in incal.gyro_rate.__doc__
    for e in incal.REGISTRY:
        if e["input"] == "recording":
            f = getattr(incal, e["python"]["function"])
            names = {incal._keyword(a["name"]) for a in e["arguments"]["reduce"]} - {"input", "json", "output"}
            assert set(inspect.signature(f).parameters) == {"data", "progress"} | names, e["id"]
    with pytest.raises(TypeError, match="unexpected keyword argument 'mont'"):
        incal.tumble(str(recordings["tumble"]), mont="pendulum")


def test_progress_goes_to_a_callable_and_its_exception_is_raised():
    rng = np.random.default_rng(3)
    y = rng.normal(0.0, 0.01, 200_000)
    seen = []
    r = incal.noise(y, rate_hz=100.0, progress=lambda stage, done, total: seen.append((stage, done, total)))
    assert seen, "the noise analysis reports its stages"
    stages = {s for s, _, _ in seen}
    for s in stages:
        steps = [(d, t) for st, d, t in seen if st == s]
        assert steps[0][0] == 0 and steps[-1][0] == steps[-1][1], (s, steps[:3], steps[-1])
        assert all(a[0] <= b[0] for a, b in zip(steps, steps[1:])), s
    assert len(seen) < 500, "reports are throttled"
    assert r.document == incal.noise(y, rate_hz=100.0).document

    class Stop(Exception):
        pass

    def stop(stage, done, total):
        raise Stop(stage)

    with pytest.raises(Stop):
        incal.noise(y, rate_hz=100.0, progress=stop)
    with pytest.raises(TypeError, match="progress"):
        incal.noise(y, rate_hz=100.0, progress="yes")


def test_calls_from_several_threads_equal_the_serial_ones(recordings):
    """The GIL is released while the core works: four threads reduce at
    once and each gets the serial document."""
    from concurrent.futures import ThreadPoolExecutor

    jobs = []
    for name, _, _, options in CASES[:6]:
        frame = incal._read_csv(recordings[name].read_bytes())
        jobs.append((name, frame, options, getattr(incal, name)(frame, **options).document))
    with ThreadPoolExecutor(4) as pool:
        docs = list(pool.map(lambda j: getattr(incal, j[0])(j[1], **j[2]).document, jobs * 3))
    for (name, _, _, serial), doc in zip(jobs * 3, docs):
        assert doc == serial, name


def test_a_result_shows_its_plots_inline_and_a_bad_file_is_refused(tmp_path):
    data, _ = incal.simulate.tumble(seed=7)
    r = incal.tumble(data, mount="pendulum")
    svgs = r.figures()
    assert svgs and all(s.lstrip().startswith("<svg") for s in svgs), svgs[0][:80]
    html = r._repr_html_()
    assert html.count("<svg") == len(svgs) and "K1" in html
    good = tmp_path / "r.json"
    r.to_json(str(good))
    assert incal.read_result(str(good)).document == r.document
    doc = json.loads(good.read_text())
    doc["coefficients"]["K1"]["U95"] *= 3
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(incal.InputError, match=r"coefficients\.K1\.U95") as e:
        incal.read_result(str(bad))
    assert e.value.file == str(bad)


PAPER_TOML = """
[[accelerometer]]
name = "a"
position_m = [0.1, 0.0, 0.0]
direction = [0.0, 0.0, 1.0]
[[accelerometer]]
name = "b"
position_m = [-0.1, 0.0, 0.0]
direction = [0.0, 0.0, 1.0]
[[accelerometer]]
name = "c"
position_m = [0.0, 0.1, 0.0]
direction = [1.0, 0.0, 0.0]
[[accelerometer]]
name = "d"
position_m = [0.0, -0.1, 0.0]
direction = [1.0, 0.0, 0.0]
[[accelerometer]]
name = "e"
position_m = [0.0, 0.0, 0.1]
direction = [0.0, 1.0, 0.0]
[[accelerometer]]
name = "f"
position_m = [0.0, 0.0, -0.1]
direction = [0.0, 1.0, 0.0]
"""


def test_a_file_option_is_read_as_the_cli_reads_it(recordings, tmp_path):
    """The gyro-free unit's geometry file: its name, hash and text go to
    the core, and the document is the CLI's."""
    name, words, _, options = next(c for c in CASES if c[0] == "gfimu_calibrate")
    geometry = tmp_path / "paper.toml"
    geometry.write_text(PAPER_TOML)
    path = recordings[name]
    options = {k: v for k, v in options.items() if k not in ("layout", "lever_arm_m")}
    got = incal.gfimu_calibrate(str(path), geometry=str(geometry), **options).document
    expected = json.loads(
        cli(words + ["--input", path, "--json", "--geometry", geometry] + flags(options))
    )
    assert got == expected
    with pytest.raises(incal.InputError) as e:
        incal.gfimu_calibrate(str(path), geometry=str(tmp_path / "missing.toml"))
    assert e.value.file == str(tmp_path / "missing.toml")


def test_a_result_document_option_is_a_result_or_its_path(tmp_path):
    """Centrifuge's ``from_`` and gyro positions' ``k1_from`` read another
    result: from its path the document is the CLI's ``--from``; from the
    ``incal.Result`` itself the same but for the input's name."""
    cli(["simulate", "tumble", "--k0", "1.2e-4", "--k1", "1.3", "--seed", "21", "-o", tmp_path / "t.csv"])
    cli(["tumble", "--mount", "pendulum", "--input", tmp_path / "t.csv", "--json", "-o", tmp_path / "t.json"])
    cli(["simulate", "centrifuge", "--seed", "22", "-o", tmp_path / "c.csv"])
    words = ["centrifuge", "--input", tmp_path / "c.csv", "--radius-m", "0.71", "--latitude-deg", "39.9"]
    expected = json.loads(cli(words + ["--from", tmp_path / "t.json", "--json"]))
    got = incal.centrifuge(str(tmp_path / "c.csv"), radius_m=0.71, latitude_deg=39.9, from_=str(tmp_path / "t.json"))
    assert got.document == expected
    tumble = incal.read_result(str(tmp_path / "t.json"))
    held = incal.centrifuge(str(tmp_path / "c.csv"), radius_m=0.71, latitude_deg=39.9, from_=tumble)
    assert held.coefficients == got.coefficients
    assert [i for i in held.document["inputs"] if i["role"] == "from"][0]["path"] == "<Result>"

    cli(["simulate", "gyro-rate", "-o", tmp_path / "r.csv"])
    cli(["gyro", "rate", "--input", tmp_path / "r.csv", "--latitude-deg", "45", "--json", "-o", tmp_path / "r.json"])
    cli(["simulate", "gyro-positions", "--latitude-deg", "30", "--azimuths-deg", "60", "--axial", "oa", "-o", tmp_path / "p.csv"])
    words = ["gyro", "positions", "--input", tmp_path / "p.csv", "--latitude-deg", "30", "--azimuth-deg", "60", "--axial", "oa"]
    expected = json.loads(cli(words + ["--from", tmp_path / "r.json", "--json"]))
    got = incal.gyro_positions(
        str(tmp_path / "p.csv"), latitude_deg=30, azimuth_deg=60, axial="oa", k1_from=str(tmp_path / "r.json")
    )
    assert got.document == expected
    with pytest.raises(incal.InputError, match="gyro-rate result") as e:
        incal.gyro_positions(str(tmp_path / "p.csv"), latitude_deg=30, azimuth_deg=60, axial="oa", k1_from=tumble)
    assert e.value.option == "k1_from"


def test_records_work_on_the_records_crate(tmp_path):
    """incal.Records without the command line: add (once), list, show,
    history, verify, export and import, and the identity refused as the
    CLI refuses it (naming the keyword)."""
    data, _ = incal.simulate.tumble(seed=7)
    r = incal.tumble(data, mount="pendulum", serial="SN-7")
    store = incal.Records(tmp_path / "lab.db")
    first = store.add(r, operator="lee")
    assert store.add(r, operator="lee") == first, "the same document is stored once"
    assert [x["id"] for x in store.list()] == [first]
    shown = store.show(first)
    assert shown["serial"] == "SN-7" and shown["result"] == r.document
    assert store.history("SN-7", "K1")["points"]
    v = store.verify()
    assert v["records"] == 1 and len(v["head"]) == 64
    assert store.export(tmp_path / "lab.jsonl")["head"] == v["head"]
    other = incal.Records(tmp_path / "copy.db")
    assert other.import_(tmp_path / "lab.jsonl")["added"] == 1
    with pytest.raises(incal.InputError, match="serial 'SN-8' differs from <Result>'s instrument.serial 'SN-7'"):
        store.add(r, serial="SN-8")
    with pytest.raises(incal.InputError, match="no instrument.serial: give serial="):
        store.add(incal.tumble(data, mount="pendulum"))
    with pytest.raises(incal.InputError, match="reason: empty"):
        store.supersede(first, r, " ")
    with pytest.raises(incal.InputError, match="missing.db"):
        incal.Records(tmp_path / "missing.db").list()


def test_a_report_is_written_by_the_report_crate(tmp_path):
    data, _ = incal.simulate.tumble(seed=7)
    r = incal.tumble(data, mount="pendulum", serial="SN-7")
    limits = tmp_path / "l.toml"
    limits.write_text("[tumble]\nK1 = { min = 9.9, max = 10.1 }\n")
    ours = pathlib.Path(r.report(str(tmp_path / "a.html"), limits=str(limits))).read_text()
    path = tmp_path / "r.json"
    r.to_json(str(path))
    cli(["report", path, "--limits", limits, "-o", tmp_path / "b.html"])
    theirs = (tmp_path / "b.html").read_text()
    # The same report but for the time it was made.
    import re

    stamp = re.compile(r"\d{4}-\d\d-\d\d[ T]\d\d:\d\d(:\d\d)?( UTC|Z)?")
    assert stamp.sub("T", ours) == stamp.sub("T", theirs)
    assert "<svg" in ours and "pass" in ours
    with pytest.raises(incal.InputError, match="l2.toml"):
        (tmp_path / "l2.toml").write_text("[tumble]\nK1 = { mni = 1 }\n")
        r.report(str(tmp_path / "c.html"), limits=str(tmp_path / "l2.toml"))
