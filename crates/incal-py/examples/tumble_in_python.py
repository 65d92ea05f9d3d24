"""A tumble calibration in Python, start to finish: simulate a recording
from a known truth, check the plan, reduce it three ways (file, DataFrame,
arrays), judge it, write the certificate. Run: python tumble_in_python.py
OUTDIR (the tests run it)."""

import pathlib
import sys

import incal

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out.mkdir(parents=True, exist_ok=True)

# The plan first: the predicted u of every coefficient of the GJB 12-point
# plan for K1 = 10 output/g and a 1 µ-output noise per sample.
plan = incal.plan.tumble(k1=10, noise=1e-6, samples=10)
print("predicted u(K1):", plan["predicted_u"]["K1"], plan["units"]["K1"])

# A recording with a known truth (seed 7), as a DataFrame.
data, notes = incal.simulate.tumble(seed=7)
csv = out / "t.csv"
data.to_csv(csv, index=False)

# The same reduction from the file, the DataFrame and the arrays.
by_file = incal.tumble(str(csv), mount="pendulum", serial="SN-7")
by_frame = incal.tumble(data, mount="pendulum", serial="SN-7")
by_arrays = incal.tumble(
    angle_deg=data["angle_deg"].to_numpy(),
    output=data["output"].to_numpy(),
    mount="pendulum",
    serial="SN-7",
)
assert by_file.coefficients == by_frame.coefficients == by_arrays.coefficients
print(by_file.to_dataframe()[["value", "U95", "unit"]])

# Limits, the verdict and the certificate.
limits = out / "limits.toml"
limits.write_text('rule = "guard-band"\n[tumble]\nK1 = { min = 9.99, max = 10.01 }\n')
judged = incal.tumble(str(csv), mount="pendulum", serial="SN-7", limits=str(limits))
print("verdict:", judged.document["verdict"])
print("certificate:", judged.report(str(out / "t.html")))
