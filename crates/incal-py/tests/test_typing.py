"""The stubs are the registry's, and a type checker uses them: mypy
--strict passes a typed script and finds each mistake of another one."""

import os
import pathlib
import subprocess
import sys

import incal
from incal import _stubs

HERE = pathlib.Path(__file__).resolve().parent
PACKAGE = HERE.parent / "python" / "incal"


def test_the_stubs_are_generated_from_the_registry():
    parts = _stubs.generate(incal.REGISTRY)
    init = (PACKAGE / "__init__.pyi").read_text()
    assert init.split(_stubs.BEGIN)[1] == parts["__init__.pyi"].split(_stubs.BEGIN)[1], (
        "run: python -m incal._stubs crates/incal-py/python/incal"
    )
    for name in ("plan.pyi", "simulate.pyi"):
        assert (PACKAGE / name).read_text() == parts[name], f"{name}: run python -m incal._stubs"


def test_the_stubs_list_every_option_of_the_command():
    init = (PACKAGE / "__init__.pyi").read_text()
    for e in incal.REGISTRY:
        if e["input"] != "recording":
            continue
        block = init.split(f"def {e['python']['function']}(")[1].split(") -> Result")[0]
        for a in e["arguments"]["reduce"]:
            if a["name"] not in _stubs.NOT_KEYWORDS:
                assert f"    {_stubs.keyword(a['name'])}: " in block, (e["id"], a["name"])


def mypy(script: pathlib.Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", "--ignore-missing-imports", str(script)],
        capture_output=True,
        text=True,
        cwd=str(HERE),
        env={**os.environ, "MYPYPATH": ""},
    )


def test_mypy_strict_passes_typed_code():
    r = mypy(HERE / "typing" / "good.py")
    assert r.returncode == 0, r.stdout + r.stderr


def test_mypy_strict_finds_a_misspelt_option_a_bad_value_and_a_missing_one():
    r = mypy(HERE / "typing" / "bad.py")
    assert r.returncode == 1, r.stdout + r.stderr
    out = r.stdout
    assert 'Unexpected keyword argument "noize"' in out, out
    assert "Literal['sideways']" in out, out
    assert 'Missing named argument "latitude_deg"' in out, out
    assert 'Argument "k1" to "tumble" has incompatible type "str"' in out, out
    assert out.count("error:") == 4, out
