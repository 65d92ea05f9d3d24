"""The Digital Calibration Certificate (PTB DCC 3.2.0 XML, D-SI 2.1.0
quantities) written by ``incal report --dcc``: valid against the schemas
kept as fixtures (offline, with their licence), every coefficient's value
and expanded uncertainty carried to the double's last bits, and a damaged certificate
refused by the same validation (so the check can fail)."""

import json
import math
import os
import pathlib
import subprocess
import xml.etree.ElementTree as ET

import pytest
import xmlschema

ROOT = pathlib.Path(__file__).resolve().parents[3]
BIN = os.environ.get("INCAL_BIN", str(ROOT / "target" / "debug" / "incal"))
XSD = ROOT / "crates" / "incal-report" / "tests" / "dcc"
NS = {"dcc": "https://ptb.de/dcc", "si": "https://ptb.de/si"}
LAB = """[lab]
name = "Inertial Test Laboratory <ITL> & Co"
address = "1 Gyro Road\\nTianjin 300000, China"
certificate_prefix = "ITL-"
country = "CN"

[[signatory]]
name = "Li Wei"
role = "Head of calibration"
"""


@pytest.fixture(scope="module")
def schema():
    return xmlschema.XMLSchema(
        str(XSD / "dcc_3_2_0.xsd"),
        locations=[("https://ptb.de/si", str(XSD / "dsi_2_1_0.xsd")),
                   ("http://www.w3.org/2000/09/xmldsig#", str(XSD / "ds_0_1.xsd"))],
        allow="local",
    )


def incal(*args):
    p = subprocess.run([BIN, *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return p.stdout


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A tumble and a gyro rate result, and the lab profile."""
    d = tmp_path_factory.mktemp("dcc")
    incal("simulate", "tumble", "--k0", "8e-3", "--seed", 1, "-o", d / "t.csv")
    incal("tumble", "--mount", "pendulum", "--input", d / "t.csv", "--serial", "SN <1>",
          "--model", "QA-2000", "--json", "-o", d / "t.json")
    incal("simulate", "gyro-rate", "--seed", 2, "-o", d / "g.csv")
    incal("gyro", "rate", "--input", d / "g.csv", "--latitude-deg", 39.1, "--serial", "G-7", "--json", "-o", d / "g.json")
    (d / "lab.toml").write_text(LAB)
    return d


@pytest.mark.parametrize("name", ["t", "g"])
def test_dcc_is_valid_and_carries_every_coefficient(schema, results, name):
    out = results / f"{name}.xml"
    incal("report", results / f"{name}.json", "--lab", results / "lab.toml", "--dcc", "--customer", "ACME", "-o", out)
    schema.validate(out.read_text())
    doc = json.loads((results / f"{name}.json").read_text())
    root = ET.parse(out).getroot()
    got = {}
    for r in root.iterfind(".//dcc:result", NS):
        key = r.find("dcc:name/dcc:content", NS).text
        real = r.find(".//si:real", NS)
        got[key] = (float(real.find("si:value", NS).text),
                    float(real.find("si:expandedUnc/si:uncertainty", NS).text),
                    float(real.find("si:expandedUnc/si:coverageFactor", NS).text))
    assert set(got) == set(doc["coefficients"])
    for key, c in doc["coefficients"].items():
        value, u95, k = got[key]
        # To the double's last bits (the document is read back through
        # its units, which may move the last one).
        assert math.isclose(value, c["value"], rel_tol=1e-14), key
        assert math.isclose(u95, c["U95"], rel_tol=1e-14), key
        assert abs(k - c["k95"]) < 1e-3, key
    assert root.find(".//dcc:uniqueIdentifier", NS).text.startswith("ITL-")
    assert root.find(".//dcc:customer/dcc:name/dcc:content", NS).text == "ACME"


def test_a_damaged_certificate_is_refused(schema, results):
    out = results / "t.xml"
    incal("report", results / "t.json", "--lab", results / "lab.toml", "--dcc", "-o", out)
    text = out.read_text()
    for bad in [text.replace("<si:coverageProbability>0.95", "<si:coverageProbability>1.5", 1),
                text.replace("<dcc:countryCodeISO3166_1>CN", "<dcc:countryCodeISO3166_1>China", 1),
                text.replace("<dcc:coreData>", "<dcc:coreData><dcc:nonsense/>", 1)]:
        assert bad != text
        with pytest.raises(xmlschema.XMLSchemaValidationError):
            schema.validate(bad)


def test_dcc_needs_a_lab(results):
    p = subprocess.run([BIN, "report", str(results / "t.json"), "--dcc"], capture_output=True, text=True)
    assert p.returncode == 2 and "--lab" in p.stderr
