"""Batch reduction on a Dask LocalCluster of two worker processes, and
records on SQLite and on a real PostgreSQL server (a throwaway one,
started by ``scripts/pg-test-server.sh`` for this test session)."""

import json
import os
import pathlib
import subprocess

import pytest

import incal

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    """50 tumble recordings named by serial, 3 of them corrupt."""
    d = tmp_path_factory.mktemp("line")
    paths = []
    for k in range(50):
        p = d / f"SN-{k:04d}.csv"
        if k in (7, 23, 41):
            text = {7: "angle_deg,output\n0,1\n90,oops\n", 23: "", 41: "angle_deg\n0\n"}[k]
            p.write_text(text)
        else:
            incal.run(["simulate", "tumble", "--seed", k, "--k0", f"{k}e-5", "--samples", "3", "-o", p])
        paths.append(str(p))
    return paths


@pytest.fixture(scope="module")
def pg_url():
    """A PostgreSQL server for this test process (stopped when it ends)."""
    out = subprocess.run(
        ["bash", str(ROOT / "scripts" / "pg-test-server.sh"), str(os.getpid())],
        capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def serial_run(paths):
    docs = {}
    for p in paths:
        serial = pathlib.Path(p).stem
        try:
            docs[p] = incal.tumble(p, mount="pendulum", serial=serial).document
        except incal.InputError as e:
            docs[p] = e
    return docs


def test_batch_on_a_two_worker_local_cluster_equals_the_serial_run(recordings, tmp_path):
    from distributed import Client, LocalCluster

    store = str(tmp_path / "line.db")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        b = incal.batch.reduce(recordings, "tumble", client=client, records=store,
                               serial_from_stem=True, mount="pendulum", progress=False)
        again = incal.batch.reduce(recordings, "tumble", client=client, records=store,
                                   serial_from_stem=True, mount="pendulum", progress=False)
    assert len(b) == 50 and len(b.results) == 47 and len(b.errors) == 3
    serial = serial_run(recordings)
    for p, r in zip(recordings, b):
        if isinstance(serial[p], Exception):
            assert isinstance(r, incal.batch.FileError)
            assert r.message == str(serial[p]) and r.code == 2
            assert pathlib.Path(p).name in r.message, "the error names the file"
        else:
            assert r.document == serial[p], p
    assert sorted(pathlib.Path(p).name for p in b.errors) == ["SN-0007.csv", "SN-0023.csv", "SN-0041.csv"]
    # Records: one per good recording, in order, written once.
    ids = [i for i in b.record_ids if i is not None]
    assert ids == list(range(1, 48))
    assert again.record_ids == b.record_ids, "a second run stores nothing twice"
    rec = incal.Records(store)
    listed = rec.list()
    assert len(listed) == 47
    assert len({r["serial"] for r in listed}) == 47
    assert rec.verify()["records"] == 47


def test_batch_without_a_client_starts_its_own_cluster(recordings):
    b = incal.batch.reduce(recordings[5:9], "tumble", mount="pendulum", progress=False)
    assert [type(r).__name__ for r in b] == ["Result", "Result", "FileError", "Result"]
    assert b[0].document == incal.tumble(recordings[5], mount="pendulum").document
    with pytest.raises(incal.InputError, match="'wobble' is not a procedure"):
        incal.batch.reduce(recordings[:1], "wobble")


def test_the_cli_batch_equals_the_dask_batch(recordings, tmp_path):
    # The CLI exits 2 when some recordings are refused: read its summary
    # from a file it writes before exiting.
    summary = tmp_path / "summary.json"
    with pytest.raises(incal.InputError, match="1 of 12 recordings refused"):
        incal.run(["batch", "tumble"] + recordings[:12] + ["--jobs", "2", "--json", "--serial-from-stem",
                   "-o", summary, "--", "--mount", "pendulum"])
    cli = json.loads(summary.read_text())
    serial = serial_run(recordings[:12])
    assert cli["ok"] == 11 and cli["failed"] == 1
    for item in cli["results"]:
        want = serial[item["input"]]
        if item["ok"]:
            assert item["result"] == want
        else:
            assert item["error"] == str(want)


def test_records_move_from_sqlite_to_postgresql(tmp_path, pg_url, recordings):
    lite = incal.Records(tmp_path / "lab.db")
    results = [incal.tumble(p, mount="pendulum", serial="SN-A") for p in recordings[:3]]
    for r, day in zip(results, ["2025-01-01", "2025-02-01", "2025-03-01"]):
        lite.add(r, created_utc=day)
    lite.supersede(2, incal.tumble(recordings[4], mount="pendulum", serial="SN-A"), "wrong mount noted")
    export = tmp_path / "lab.jsonl"
    lite.export(export)
    pg = incal.Records(pg_url)
    done = pg.import_(export)
    assert done["added"] == 4 and done["present"] == 0
    assert pg.verify() == lite.verify()
    assert pg.list() == lite.list()
    assert pg.history("SN-A", "K0") == lite.history("SN-A", "K0")
    assert pg.show(4) == lite.show(4)
    assert pg.import_(export)["added"] == 0
    # A batch writing its records to the PostgreSQL store.
    b = incal.batch.reduce(recordings[10:14], "tumble", records=pg_url, serial_from_stem=True,
                           mount="pendulum", progress=False)
    assert b.record_ids == [5, 6, 7, 8]
    assert pg.verify()["records"] == 8
    with pytest.raises(incal.InputError, match="cannot connect") as e:
        incal.Records("postgresql://lab:s3cret@127.0.0.1:1/none").verify()
    assert "s3cret" not in str(e.value)


def test_a_fail_on_verdict_keeps_and_records_the_result(recordings, tmp_path):
    limits = tmp_path / "l.toml"
    limits.write_text("[tumble]\nK1 = { max = 1 }\n")  # every K1 is near 10: fail
    store = str(tmp_path / "stop.db")
    b = incal.batch.reduce(recordings[:2], "tumble", records=store, serial_from_stem=True,
                           mount="pendulum", limits=limits, fail_on="fail", progress=False)
    assert [type(r).__name__ for r in b] == ["Result", "Result"]
    assert all(r.document["verdict"] == "fail" for r in b)
    assert sorted(b.stopped) == sorted(recordings[:2])
    assert all("stopped by fail_on='fail'" in m for m in b.stopped.values())
    assert b.record_ids == [1, 2]


def test_units_of_one_fixture_equal_the_cli_and_the_one_unit_files(recordings, tmp_path):
    """Three units in one file (recordings 0, 1 and 7, the last corrupt in
    its own column): each its own result, the bad one its own error, as
    `incal batch --units` gives them."""
    import csv

    cols = []
    for k in (0, 1, 2):
        with open(recordings[k]) as f:
            rows = [r for r in csv.reader(l for l in f if not l.startswith("#"))]
        cols.append(rows)
    fixture = tmp_path / "fixture.csv"
    with open(fixture, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["angle_deg", "out_1", "out_2", "out_3"])
        for k, r in enumerate(cols[0][1:]):
            w.writerow([r[0], r[1], cols[1][k + 1][1], "oops" if k == 4 else cols[2][k + 1][1]])
    units = {"SN-A": "out_1", "SN-B": "out_2", "SN-C": "out_3"}
    b = incal.batch.reduce([fixture], "tumble", units=units, mount="pendulum", progress=False)
    assert b.paths == [f"{fixture} [SN-A]", f"{fixture} [SN-B]", f"{fixture} [SN-C]"]
    for r, k in zip(b[:2], (0, 1)):
        alone = incal.tumble(recordings[k], mount="pendulum").document
        assert r.document["coefficients"] == alone["coefficients"]
    assert [r.document["instrument"]["serial"] for r in b[:2]] == ["SN-A", "SN-B"]
    err = b[2]
    assert isinstance(err, incal.batch.FileError) and err.code == 2
    assert err.message.endswith("(unit SN-C)") and "fixture.csv:6" in err.message
    summary = tmp_path / "units.json"
    with pytest.raises(incal.InputError, match="1 of 3 units refused"):
        incal.run(["batch", "tumble", fixture, "--units", "SN-A=out_1,SN-B=out_2,SN-C=out_3", "--json",
                   "-o", summary, "--", "--mount", "pendulum"])
    cli = json.loads(summary.read_text())
    for item, r in zip(cli["results"], b):
        if item["ok"]:
            assert item["result"] == r.document
        else:
            assert item["error"] == r.message
    with pytest.raises(incal.InputError, match="serial 'X' given twice"):
        incal.batch.reduce([fixture], "tumble", units="X=out_1,X=out_2", progress=False)


def test_a_units_slot_joins_the_batchs_meta(recordings, tmp_path):
    fixture = tmp_path / "pair.csv"
    a = [l for l in open(recordings[0]) if not l.startswith("#")]
    b = [l for l in open(recordings[1]) if not l.startswith("#")]
    with open(fixture, "w") as f:
        f.write("angle_deg,out_1,out_2\n")
        for x, y in zip(a[1:], b[1:]):
            f.write(f"{x.strip()},{y.strip().split(',')[1]}\n")
    mapping = tmp_path / "units.csv"
    mapping.write_text("serial;columns;slot\nU1;out_1;4\nU2;out_2;5\n")
    got = incal.batch.reduce([fixture], "tumble", units=mapping, meta={"operator": "lee"}, mount="pendulum", progress=False)
    assert [r.document["instrument"]["slot"] for r in got] == ["4", "5"]
    assert [r.document["instrument"]["operator"] for r in got] == ["lee", "lee"]
    with pytest.raises(incal.InputError, match="no such mapping file"):
        incal.batch.reduce([fixture], "tumble", units=tmp_path / "missing.csv", progress=False)
    mapping.write_text("serial,columns,options\nU1,out_1,--mount=gate\n")
    with pytest.raises(incal.InputError, match="unit U1: mount is given by the batch too"):
        incal.batch.reduce([fixture], "tumble", units=mapping, mount="pendulum", progress=False)
