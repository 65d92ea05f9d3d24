"""incal against its Python peers, side by side in one process.

    python crates/incal-py/bench/side_by_side.py [--quick]

1. Noise: ``incal.noise`` (five deviations OADEV, MDEV, OHDEV, TDEV, TOTDEV
   at octave taus with confidence bounds, noise identification, IEEE 952
   term fit, bias stability) against allantools' five deviations alone
   (``oadev``, ``mdev``, ``ohdev``, ``tdev``, ``totdev``, ``taus="octave"``)
   on the same float64 numpy array of 10^6 and 10^7 samples (white noise
   plus a rate random walk, seeded). incal reads the array in place. The
   OADEV of both is compared at every common tau.
2. IMU: ``incal.imu_ferraris`` against imucal's ``FerrarisCalibration`` on
   imucal's own example session (``annotated_session.csv``, 204.8 Hz, kept
   with its MIT license in ``crates/incal/tests/fixtures/imucal``); the
   matrices are compared.

3. Data in memory: ``incal.tumble`` on a 720,000-row recording (720
   positions of 1,000 samples) from a pandas DataFrame, against the same
   call from its CSV path and against pandas' own ``read_csv`` +
   ``groupby`` of that file (what a notebook user does first);
   ``incal.imu_autocal`` on a 10^6-row recording from a DataFrame against
   the same call from its CSV path. The documents' coefficients agree.

Every timing is the best of ``repeat`` runs of the whole call, wall clock,
in this process. Needs the incal package, numpy, pandas, allantools and
imucal (``pip install allantools imucal``). ``--quick`` stops at 10^6.
"""

import pathlib
import sys
import time

import numpy as np
import pandas as pd

import incal

ROOT = pathlib.Path(__file__).resolve().parents[3]
SESSION = ROOT / "crates" / "incal" / "tests" / "fixtures" / "imucal" / "annotated_session.csv"


def best(f, repeat):
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return min(times), out


def record(n, rate_hz, seed=7):
    rng = np.random.default_rng(seed)
    white = rng.normal(0.0, 0.01, n)
    walk = np.cumsum(rng.normal(0.0, 1e-5, n))
    return white + walk


def oadev_of(doc):
    """The OADEV column of the channel's stability table, by tau (s)."""
    for t in doc["tables"]:
        names = [c["name"] for c in t["columns"]]
        if t["id"].startswith("stability.") and "tau" in names and "oadev" in names:
            i, j = names.index("tau"), names.index("oadev")
            return {round(r[i], 9): r[j] for r in t["rows"] if r[j] is not None}
    return {}


def noise(n, rate_hz=100.0):
    import allantools

    x = record(n, rate_hz)
    repeat = 7 if n <= 1_000_000 else 1
    t_incal, r = best(lambda: incal.noise(gx=x, rate_hz=rate_hz, quantity="gyro"), repeat)

    def five():
        out = {}
        for name in ["oadev", "mdev", "ohdev", "tdev", "totdev"]:
            out[name] = getattr(allantools, name)(x, rate=rate_hz, data_type="freq", taus="octave")
        return out

    t_at, at = best(five, repeat)
    ours = oadev_of(r.document)
    taus, devs = at["oadev"][0], at["oadev"][1]
    worst = 0.0
    common = 0
    for tau, dev in zip(taus, devs):
        key = round(float(tau), 9)
        if key in ours:
            common += 1
            worst = max(worst, abs(ours[key] - dev) / dev)
    return t_incal, t_at, common, worst


def ferraris():
    from imucal import FerrarisCalibration, ferraris_regions_from_df

    def theirs():
        # Reading the file is timed on both sides.
        frame = pd.read_csv(SESSION, header=0, index_col=[0, 1])
        regions = ferraris_regions_from_df(frame)
        cal = FerrarisCalibration(grav=9.81, expected_angle=-360)
        return cal.compute(regions, sampling_rate_hz=204.8, from_acc_unit="a.u.", from_gyr_unit="a.u.")

    t_incal, r = best(lambda: incal.imu_ferraris(SESSION, rate_hz=204.8, gravity_m_s2=9.81), 5)
    t_imucal, c = best(theirs, 5)
    worst = 0.0
    for k in ["K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"]:
        a, b = np.asarray(r.document[k], float), np.asarray(getattr(c, k), float)
        worst = max(worst, float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300))))
    return t_incal, t_imucal, worst


def tumble_in_memory(tmp):
    rng = np.random.default_rng(1)
    angle = np.repeat(np.arange(0.0, 360.0, 0.5), 1000)
    g = np.sin(np.radians(angle))
    y = 1e-3 + 10.0 * g + 1e-4 * g * g + rng.normal(0.0, 1e-4, angle.size)
    path = tmp / "tumble720k.csv"
    pd.DataFrame({"angle_deg": angle, "output": y}).to_csv(path, index=False)
    frame = pd.read_csv(path)
    t_path, a = best(lambda: incal.tumble(str(path), mount="pendulum"), 5)
    t_frame, b = best(lambda: incal.tumble(frame, mount="pendulum"), 5)
    t_pandas, _ = best(lambda: pd.read_csv(path).groupby("angle_deg")["output"].agg(["mean", "std", "count"]), 5)
    same = all(a.coefficients[k].value == b.coefficients[k].value for k in a.coefficients)
    return t_frame, t_path, t_pandas, same


def autocal_in_memory(tmp):
    frame, _ = incal.simulate.imu(
        sequence="random", rate_hz=200, orientations=40, init_static_s=60, static_s=120, move_s=3, seed=5
    )
    frame = frame.iloc[: 1_000_000]
    path = tmp / "autocal.csv"
    frame.to_csv(path, index=False)
    frame = pd.read_csv(path)
    t_path, a = best(lambda: incal.imu_autocal(str(path), rate_hz=200), 3)
    t_frame, b = best(lambda: incal.imu_autocal(frame, rate_hz=200), 3)
    same = all(a.coefficients[k].value == b.coefficients[k].value for k in a.coefficients)
    return len(frame), t_frame, t_path, same


def main():
    quick = "--quick" in sys.argv
    print(f"incal {incal.__version__}, numpy {np.__version__}")
    rows = []
    for n in [1_000_000] + ([] if quick else [10_000_000]):
        t_i, t_a, common, worst = noise(n)
        rows.append((f"noise, {n:.0e} samples", t_i, "allantools (5 deviations)", t_a, f"OADEV at {common} taus within {worst:.1e}"))
    t_i, t_m, worst = ferraris()
    rows.append(("imu_ferraris, imucal example", t_i, "imucal FerrarisCalibration", t_m, f"matrices within {worst:.1e}"))
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        tmp = pathlib.Path(d)
        t_f, t_p, t_pd, same = tumble_in_memory(tmp)
        agree = "same coefficients" if same else "COEFFICIENTS DIFFER"
        rows.append(("tumble 720k rows, DataFrame", t_f, "incal.tumble from the path", t_p, agree))
        rows.append(("tumble 720k rows, DataFrame", t_f, "pandas read_csv + groupby", t_pd, "(what pandas does alone)"))
        n, t_f, t_p, same = autocal_in_memory(tmp)
        agree = "same coefficients" if same else "COEFFICIENTS DIFFER"
        rows.append((f"imu_autocal {n:.0e} rows, DataFrame", t_f, "incal.imu_autocal from the path", t_p, agree))
    print()
    print(f"{'case':32} {'incal s':>9} {'peer':28} {'peer s':>9} {'ratio':>7}  agreement")
    for case, ti, peer, tp, agree in rows:
        print(f"{case:32} {ti:9.3f} {peer:28} {tp:9.3f} {tp / ti:6.1f}x  {agree}")


if __name__ == "__main__":
    main()
