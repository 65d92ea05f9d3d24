"""The package runs on the core crates alone: plans by simulation, the
simulators' truth, run sheets, reports and soak fits from a records store
come from the core, not from the command line, and equal what the CLI
writes for the same call."""

import json
import os
import pathlib
import re
import subprocess

import pytest

import incal

ROOT = pathlib.Path(__file__).resolve().parents[3]
BIN = os.environ.get("INCAL_BIN", str(ROOT / "target" / "debug" / "incal"))


def cli(words):
    r = subprocess.run([BIN] + [str(w) for w in words], capture_output=True)
    assert r.returncode == 0, r.stderr.decode()
    return r.stdout


def test_the_extension_builds_without_the_command_line():
    manifest = (ROOT / "crates" / "incal-py" / "Cargo.toml").read_text()
    assert "incal-cli" not in manifest
    assert not hasattr(incal._incal, "_run")


def test_the_shipped_argument_tables_are_the_clis():
    registry = json.loads(cli(["procedures", "--json"]))
    assert [e["id"] for e in incal.REGISTRY] == [e["id"] for e in registry]
    for ours, theirs in zip(incal.REGISTRY, registry):
        assert ours == theirs, ours["id"]


@pytest.mark.parametrize(
    "name,cli_words,kwargs",
    [
        ("imu_multipos", ["--seeds", "1", "--static-s", "0.5", "--rotations"], {"seeds": 1, "static_s": 0.5, "rotations": True}),
        ("imu_autocal", ["--seeds", "1", "--orientations", "12", "--init-static-s", "3", "--static-s", "2"],
         {"seeds": 1, "orientations": 12, "init_static_s": 3, "static_s": 2}),
        ("noise", ["--seeds", "1", "--duration-s", "200", "--rate-hz", "10", "--seed", "4", "--quantity", "accel",
                   "--vrw-ug-rthz", "50"],
         {"seeds": 1, "duration_s": 200, "rate_hz": 10, "seed": 4, "quantity": "accel", "vrw_ug_rthz": 50}),
    ],
)
def test_a_plan_by_simulation_derives_the_reduction_as_the_cli_does(name, cli_words, kwargs):
    got = getattr(incal.plan, name)(**kwargs)
    words = next(e["plan"] for e in incal.REGISTRY if e["python"]["plan"] == name).split()
    assert got == json.loads(cli(words + cli_words + ["--json"]))
    assert "reduce" in got["options"], "the derived reduction is recorded in the plan"


def test_a_run_sheet_is_the_clis(tmp_path):
    incal.plan.tumble(k1=10, noise=1e-6, samples=10, run_sheet=tmp_path / "py.csv")
    cli(["plan", "tumble", "--k1", "10", "--noise", "1e-6", "--samples", "10", "--run-sheet", tmp_path / "cli.csv"])
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    with pytest.raises(incal.InputError, match="run_sheet: a noise plan lists no settings") as e:
        incal.plan.noise(seeds=1, duration_s=100, rate_hz=10, seed=1, run_sheet=tmp_path / "n.csv")
    assert e.value.option == "run_sheet"
    assert not (tmp_path / "n.csv").exists()


@pytest.mark.parametrize(
    "name,words",
    [("gfimu", ["--seed", "15"]), ("thermal", ["--seed", "5", "--rate-hz", "1", "--hold-s", "300"]),
     ("imu", ["--sequence", "positions", "--static-s", "0.3", "--seed", "19"])],
)
def test_a_simulators_truth_is_the_clis(tmp_path, name, words):
    kwargs = {w[2:].replace("-", "_"): v for w, v in zip(words[::2], words[1::2])}
    frame, _ = getattr(incal.simulate, name)(truth_out=tmp_path / "py.json", **kwargs)
    cli(["simulate", name] + words + ["-o", tmp_path / "cli.csv", "--truth-out", tmp_path / "cli.json"])
    assert json.loads((tmp_path / "py.json").read_text()) == json.loads((tmp_path / "cli.json").read_text())
    assert frame.equals(incal._read_csv((tmp_path / "cli.csv").read_bytes()))
    if name == "gfimu":
        assert frame is not None and json.loads((tmp_path / "py.json").read_text())["notes"] == _[:]


def test_a_report_and_a_soak_fit_from_a_store_are_the_clis(tmp_path):
    db = tmp_path / "lab.db"
    store = incal.Records(db)
    for i, t in enumerate([-10, 25, 60]):
        d, _ = incal.simulate.tumble(seed=40 + i)
        r = incal.tumble(d, mount="pendulum", serial="SN-4", meta=[f"temperature_c={t}"])
        store.add(r, operator="lee")
    path = tmp_path / "r.json"
    r.to_json(str(path))
    limits = tmp_path / "l.toml"
    limits.write_text("[tumble]\nK1 = { min = 9.9, max = 10.1 }\n")
    lab = tmp_path / "lab.toml"
    lab.write_text('[lab]\nname = "Lab"\naddress = "1 Road"\ncertificate_prefix = "C-"\n'
                   '[[signatory]]\nname = "Ann"\nrole = "Head"\n')
    ours = pathlib.Path(r.report(str(tmp_path / "a.html"), limits=str(limits), db=str(db), lab=str(lab),
                                 customer="ACME")).read_text()
    cli(["report", path, "--limits", limits, "--db", db, "--lab", lab, "--customer", "ACME", "-o", tmp_path / "b.html"])
    theirs = (tmp_path / "b.html").read_text()
    stamp = re.compile(r"\d{4}-\d\d-\d\d[ T]\d\d:\d\d(:\d\d)?( UTC|Z)?")
    assert stamp.sub("T", ours) == stamp.sub("T", theirs)
    assert "C-000003" in ours and "ACME" in ours, "the record's number and the customer"
    soak = incal.thermal_fit([], db=str(db), serial="SN-4", t_ref_c=20)
    expected = json.loads(cli(["thermal", "fit", "--db", db, "--serial", "SN-4", "--t-ref-c", "20", "--json"]))
    assert soak.document == expected
    with pytest.raises(incal.InputError, match="no calibration of serial 'SN-5'"):
        incal.thermal_fit([], db=str(db), serial="SN-5")
    with pytest.raises(incal.InputError, match="date: '2026-13-01' is not a date"):
        r.report(str(tmp_path / "c.html"), lab=str(lab), date="2026-13-01")


def test_columns_are_hashed_in_their_documented_canonical_form():
    """``inputs[0].sha256`` of columns in memory is the SHA-256 of
    ``INCALCF1``, the column count, each column's kind and name, then the
    rows as little-endian binary64 (hashed beside the reduction)."""
    import hashlib
    import struct

    import numpy as np

    data, _ = incal.simulate.tumble(seed=7)
    angle = np.ascontiguousarray(data["angle_deg"], dtype=np.float64)
    out = np.ascontiguousarray(data["output"], dtype=np.float64)
    r = incal.tumble(angle_deg=angle, output=out, mount="pendulum")
    form = b"INCALCF1" + struct.pack("<I", 2)
    for name in ("angle_deg", "output"):
        form += b"\x00" + struct.pack("<I", len(name)) + name.encode()
    form += np.column_stack([angle, out]).astype("<f8").tobytes()
    assert r.document["inputs"][0]["sha256"] == hashlib.sha256(form).hexdigest()
    assert incal.tumble(data, mount="pendulum").document["inputs"][0]["sha256"] == hashlib.sha256(form).hexdigest()


def test_a_report_prints_to_pdf_or_says_why_not(tmp_path, monkeypatch):
    import shutil

    data, _ = incal.simulate.tumble(seed=7)
    r = incal.tumble(data, mount="pendulum", serial="SN-7")
    fake = tmp_path / "bin"
    fake.mkdir()
    browser = fake / "chromium"
    browser.write_text("#!/bin/sh\necho 'cannot open display' >&2\nexit 1\n")
    browser.chmod(0o755)
    real = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    with monkeypatch.context() as m:
        m.setenv("PATH", str(fake))
        with pytest.raises(incal.IncalError, match="cannot start: cannot open display") as e:
            r.report(str(tmp_path / "a.html"), pdf=True)
        assert e.value.code == 1
    assert (tmp_path / "a.html").exists(), "the HTML is kept"
    if real is None:
        pytest.skip("no Chromium here to print with")
    r.report(str(tmp_path / "b.html"), pdf=True)
    assert (tmp_path / "b.pdf").read_bytes().startswith(b"%PDF")
