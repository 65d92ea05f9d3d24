#!/usr/bin/env python3
"""The lab's web application in a real browser: headless Chromium driven
over WebDriver (Debian's chromium-driver, Python selenium).

On a fresh store made with the CLI (two instruments, one overdue; an
engineer and a signatory), against `incal serve`:

1. log in as the engineer; list the overdue instruments and open the one
   found; open the history plot of its K0;
2. submit a result document through the upload form;
3. log out, log in as the signatory, approve the submission;
4. download the certificate as PDF (with the browser's session cookie) and
   check it is a PDF of at least two pages (poppler's pdfinfo) that names
   the instrument and the approver (pdftotext).

    scripts/browser-test.py [--incal target/debug/incal] [--screenshots DIR]

With --screenshots, the main pages are saved there as PNG (the docs'
images). Exit 0 when every step passed; a step that fails raises with
what it expected and what the page showed.
"""

import argparse
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from selenium import webdriver
from selenium.webdriver.common.by import By
from selenium.webdriver.chrome.service import Service
from selenium.common.exceptions import WebDriverException

PASSWORD = "correct horse battery"
LAB = """[lab]
name = "Inertial Test Laboratory"
address = "1 Gyro Road, Tianjin 300000, China"
certificate_prefix = "ITL-"

[[signatory]]
name = "replaced by the approving account"
role = "signatory"
"""


def run(incal, *args, stdin=None, cwd=None):
    """Run incal; its standard output; a failure raises with its stderr."""
    p = subprocess.run([incal, *args], input=stdin, capture_output=True, text=True, cwd=cwd)
    if p.returncode != 0:
        raise RuntimeError(f"incal {' '.join(args)}: exit {p.returncode}: {p.stderr.strip()}")
    return p.stdout


def make_lab(incal, d):
    """A store with SN-OLD (calibrated 2024, overdue), SN-NEW (now), and
    the accounts eng (engineer) and sig (signatory); a result to submit."""
    db = str(d / "lab.db")
    for serial, k0, seed in [("SN-OLD", 8e-3, 1), ("SN-OLD", 8.05e-3, 2), ("SN-NEW", 9e-3, 3), ("SN-UP", 7e-3, 4)]:
        csv = d / f"{serial}-{seed}.csv"
        out = d / f"{serial}-{seed}.json"
        run(incal, "simulate", "tumble", "--k0", str(k0), "--seed", str(seed), "-o", str(csv))
        run(incal, "tumble", "--mount", "pendulum", "--input", str(csv), "--serial", serial,
            "--model", "QA-2000", "--json", "-o", str(out))
    run(incal, "record", "add", str(d / "SN-OLD-1.json"), "--db", db, "--operator", "lee", "--created-utc", "2023-05-01")
    run(incal, "record", "add", str(d / "SN-OLD-2.json"), "--db", db, "--operator", "lee", "--created-utc", "2024-06-01")
    run(incal, "record", "add", str(d / "SN-NEW-3.json"), "--db", db, "--operator", "kim")
    for user, role in [("eng", "engineer"), ("sig", "signatory")]:
        run(incal, "user", "add", user, "--role", role, "--db", db, stdin=PASSWORD + "\n")
    (d / "lab.toml").write_text(LAB)
    return db, d / "SN-UP-4.json"


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(incal, db, lab, port):
    proc = subprocess.Popen([incal, "serve", "--db", db, "--lab", str(lab), "--listen", f"127.0.0.1:{port}"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    for _ in range(100):
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=1) as r:
                if r.status == 200:
                    return proc
        except OSError:
            time.sleep(0.1)
        if proc.poll() is not None:
            raise RuntimeError(f"incal serve stopped: {proc.stderr.read()}")
    proc.kill()
    raise RuntimeError("incal serve did not answer /health within 10 s")


def browser(download_dir):
    o = webdriver.ChromeOptions()
    o.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    for a in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
              "--disable-background-networking", "--disable-component-update", "--disable-sync",
              "--disable-dev-shm-usage", "--window-size=1280,900"]:
        o.add_argument(a)
    o.add_experimental_option("prefs", {"download.default_directory": str(download_dir)})
    service = Service(shutil.which("chromedriver") or "/usr/bin/chromedriver")
    return webdriver.Chrome(options=o, service=service)


def expect(cond, what, drv):
    if not cond:
        body = drv.find_element(By.TAG_NAME, "body").text[:1500]
        raise AssertionError(f"{what}; the page ({drv.current_url}) shows:\n{body}")


def settled(drv, cond, what, timeout_s=30.0):
    """Wait for `cond(drv)` after a click: a click may return before the
    page it posts or follows has loaded (a check at once once read the
    login form's address with the next page already on its way)."""
    end = time.monotonic() + timeout_s
    while True:
        try:
            if cond(drv):
                return
        except WebDriverException:
            pass  # the page changed under the lookup: look again
        if time.monotonic() > end:
            expect(False, what, drv)
        time.sleep(0.1)


def login(drv, base, user):
    drv.get(base + "/login")
    drv.find_element(By.NAME, "username").send_keys(user)
    drv.find_element(By.NAME, "password").send_keys(PASSWORD)
    drv.find_element(By.ID, "login").click()
    settled(drv, lambda d: d.current_url.rstrip("/") == base, f"{user} lands on the instrument list")


def logout(drv):
    drv.find_element(By.XPATH, "//form[@action='/logout']/button").click()
    settled(drv, lambda d: d.current_url.endswith("/login"), "the logout lands on the login form")


def shot(drv, shots, name):
    if shots:
        drv.save_screenshot(str(Path(shots) / f"web-{name}.png"))


def scenario(drv, base, upload, shots, tmp):
    login(drv, base, "eng")
    footer = drv.find_element(By.ID, "chain").text
    expect(footer.startswith("Chain intact"), "the footer shows the chain intact", drv)
    shot(drv, shots, "instruments")
    # 1. The overdue instrument, its history plot.
    drv.get(base + "/?show=overdue")
    rows = drv.find_elements(By.CSS_SELECTOR, "#instruments tr td:first-child a")
    names = [r.text for r in rows]
    expect(names == ["SN-OLD"], f"only SN-OLD is overdue (got {names})", drv)
    rows[0].click()
    settled(drv, lambda d: d.current_url.endswith("/instruments/SN-OLD"), "the instrument page opens")
    expect("Instrument SN-OLD" in drv.title or "SN-OLD" in drv.page_source, "the instrument page opens", drv)
    drv.find_element(By.LINK_TEXT, "K0").click()
    settled(drv, lambda d: len(d.find_elements(By.CSS_SELECTOR, "#plot svg")) == 1, "the history page has its plot")
    expect(len(drv.find_elements(By.CSS_SELECTOR, "#history tr")) == 3, "two calibrations in the table", drv)
    shot(drv, shots, "history")
    # 2. Submit a result.
    drv.get(base + "/submit")
    drv.find_element(By.ID, "document").send_keys(str(upload))
    drv.find_element(By.ID, "submit").click()
    settled(drv, lambda d: "/records/" in d.current_url, "the submission lands on its record")
    record = drv.current_url
    expect(drv.find_element(By.ID, "state").text.startswith("submitted"), "the record awaits review", drv)
    expect(not drv.find_elements(By.ID, "approve"), "the engineer has no approve button", drv)
    logout(drv)
    # 3. Approve as the signatory.
    login(drv, base, "sig")
    drv.get(record)
    drv.find_element(By.NAME, "reason").send_keys("checked against the rig log")
    drv.find_element(By.ID, "approve").click()
    settled(drv, lambda d: d.find_element(By.ID, "state").text.startswith("approved"), "the approval is shown")
    state = drv.find_element(By.ID, "state").text
    expect(state.startswith("approved by sig (signatory)"), f"approved by sig (got {state!r})", drv)
    shot(drv, shots, "record")
    # 4. The PDF certificate, fetched with the browser's session.
    link = drv.find_element(By.ID, "certificate-pdf").get_attribute("href")
    cookie = "; ".join(f"{c['name']}={c['value']}" for c in drv.get_cookies())
    req = urllib.request.Request(link, headers={"Cookie": cookie})
    with urllib.request.urlopen(req, timeout=120) as r:
        pdf = r.read()
        kind = r.headers.get("content-type")
    expect(kind == "application/pdf" and pdf.startswith(b"%PDF"), f"a PDF (got {kind})", drv)
    path = Path(tmp) / "certificate.pdf"
    path.write_bytes(pdf)
    info = subprocess.run(["pdfinfo", str(path)], capture_output=True, text=True).stdout
    pages = int(next(line.split()[-1] for line in info.splitlines() if line.startswith("Pages:")))
    text = subprocess.run(["pdftotext", str(path), "-"], capture_output=True, text=True).stdout
    expect(pages >= 2, f"the certificate has at least 2 pages (got {pages})", drv)
    expect("SN-UP" in text and "sig" in text and "ITL-" in text,
           "the certificate names the instrument, its number and the approver", drv)
    drv.get(base + "/events")
    shot(drv, shots, "events")
    return pages


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--incal", default="target/debug/incal")
    ap.add_argument("--screenshots", default=None)
    a = ap.parse_args()
    incal = os.path.abspath(a.incal)
    with tempfile.TemporaryDirectory(prefix="incal-browser-") as tmp:
        d = Path(tmp)
        db, upload = make_lab(incal, d)
        port = free_port()
        server = start_server(incal, db, d / "lab.toml", port)
        drv = None
        try:
            drv = browser(d)
            pages = scenario(drv, f"http://127.0.0.1:{port}", upload, a.screenshots, tmp)
        finally:
            if drv is not None:
                drv.quit()
            server.terminate()
            server.wait(timeout=20)
        # The chain, after the server stopped: intact, with the approval.
        out = run(incal, "record", "verify", "--db", db)
        if not out.startswith("ok"):
            raise AssertionError(f"record verify: {out}")
    print(f"browser test: passed (login, overdue list, history plot, upload, approval, PDF of {pages} pages)")


if __name__ == "__main__":
    sys.exit(main())
