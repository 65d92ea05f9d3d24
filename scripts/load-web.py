#!/usr/bin/env python3
"""Load test of the lab's web application, on loopback, bounded in time.

    scripts/load-web.py [--incal target/release/incal] [--store sqlite|postgres|both]
                        [--readers 50] [--submitters 5] [--submit-interval 1] [--seconds 60]
                        [--instruments 100] [--records 3] [--target-ms 200]

For each store (SQLite file; PostgreSQL from scripts/pg-test-server.sh),
a lab of INSTRUMENTS instruments with RECORDS calibrations each is made
with the CLI, `incal serve` is started on it, and for SECONDS:

* READERS clients, each logged in as a viewer, read pages in a closed loop
  with no think time: the instrument list, the overdue list, an
  instrument, the history plot of its K0, a record, the audit log;
* SUBMITTERS clients, each logged in as an engineer, submit new result
  documents through the upload form, each SUBMIT_INTERVAL seconds after
  its last was answered (a person uploading files: 5 submitters at 1 s is
  about 18 000 results an hour, far above any lab's rate).

Printed per store: page views and submissions done, throughput, p50, p95,
p99 and max latency. Afterwards, with the server stopped: `incal record
verify` must pass, and every accepted submission must be stored exactly
once (its document's SHA-256 once in the store, the record count the
initial one plus the accepted). Exit 1 when the chain or a record is
wrong, or when the page views' p99 exceeds TARGET_MS.

The load generator is one asyncio thread with hand-written HTTP/1.1 over
keep-alive connections, so the client takes little of the two cores the
server shares with it.
"""

import argparse
import asyncio
import copy
import hashlib
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import time
import urllib.parse
from pathlib import Path

PASSWORD = "correct horse battery"


def run(incal, *args, stdin=None):
    p = subprocess.run([incal, *args], input=stdin, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"incal {' '.join(args[:3])}: exit {p.returncode}: {p.stderr.strip()}")
    return p.stdout


def make_documents(incal, d, instruments, records):
    """Result documents: `records` per instrument, from two simulated
    tumble results with the serial and K0 varied (each text unique)."""
    base = []
    for seed in (1, 2):
        csv, out = d / f"t{seed}.csv", d / f"t{seed}.json"
        run(incal, "simulate", "tumble", "--k0", "8e-3", "--seed", str(seed), "-o", str(csv))
        run(incal, "tumble", "--mount", "pendulum", "--input", str(csv), "--serial", "X", "--model", "QA-2000",
            "--json", "-o", str(out))
        base.append(json.loads(out.read_text()))
    docs = []
    for i in range(instruments):
        for k in range(records):
            doc = copy.deepcopy(base[k % 2])
            doc["instrument"]["serial"] = f"SN-{i:04d}"
            doc["coefficients"]["K0"]["value"] += 1e-6 * k + 1e-9 * i
            docs.append((doc, f"{2021 + k}-0{1 + i % 9}-15"))
    return docs, base[0]


def fill_store(incal, db, docs, d):
    for n, (doc, date) in enumerate(docs):
        f = d / "doc.json"
        f.write_text(json.dumps(doc))
        run(incal, "record", "add", str(f), "--db", db, "--created-utc", date, "--operator", "lee")
    run(incal, "user", "add", "reader", "--role", "viewer", "--db", db, stdin=PASSWORD + "\n")
    run(incal, "user", "add", "engineer", "--role", "engineer", "--db", db, stdin=PASSWORD + "\n")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Conn:
    """One keep-alive HTTP/1.1 connection with a session cookie."""

    def __init__(self, port):
        self.port = port
        self.reader = self.writer = None
        self.cookie = ""

    async def request(self, method, path, body=b"", ctype=None):
        if self.writer is None:
            self.reader, self.writer = await asyncio.open_connection("127.0.0.1", self.port)
        head = f"{method} {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        if self.cookie:
            head += f"Cookie: {self.cookie}\r\n"
        if body or method == "POST":
            head += f"Content-Type: {ctype}\r\nContent-Length: {len(body)}\r\n"
        self.writer.write(head.encode() + b"\r\n" + body)
        await self.writer.drain()
        status_line = await self.reader.readline()
        status = int(status_line.split()[1])
        headers = {}
        cookies = []
        while True:
            line = (await self.reader.readline()).decode("latin-1").rstrip("\r\n")
            if not line:
                break
            k, v = line.split(":", 1)
            if k.lower() == "set-cookie":
                cookies.append(v.strip())
            headers[k.lower()] = v.strip()
        if "content-length" in headers:
            data = await self.reader.readexactly(int(headers["content-length"]))
        elif headers.get("transfer-encoding") == "chunked":
            data = b""
            while True:
                size = int((await self.reader.readline()).strip(), 16)
                chunk = await self.reader.readexactly(size + 2)
                if size == 0:
                    break
                data += chunk[:-2]
        else:
            data = b""
        for c in cookies:
            kv = c.split(";")[0]
            if kv.split("=", 1)[1]:
                self.cookie = kv
        return status, headers, data.decode("utf-8", "replace")

    async def login(self, user):
        _, _, page = await self.request("GET", "/login")
        csrf = re.search(r'name="csrf" value="([0-9a-f]{64})"', page).group(1)
        form = urllib.parse.urlencode({"csrf": csrf, "username": user, "password": PASSWORD}).encode()
        status, _, _ = await self.request("POST", "/login", form, "application/x-www-form-urlencoded")
        if status != 303:
            raise RuntimeError(f"login {user}: {status}")

    def close(self):
        if self.writer is not None:
            self.writer.close()


def pct(xs, p):
    if not xs:
        return float("nan")
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(p / 100 * len(xs)))]


async def reader(port, pages, stop, lat, errors, by_page):
    c = Conn(port)
    await c.login("reader")
    k = 0
    while time.monotonic() < stop:
        path = pages[k % len(pages)]
        k += 1
        t = time.perf_counter()
        status, _, _ = await c.request("GET", path)
        lat.append(time.perf_counter() - t)
        by_page.setdefault(path.split("?")[0].split("/")[1] or "/", []).append(lat[-1])
        if status != 200:
            errors.append(f"GET {path}: {status}")
    c.close()


async def submitter(port, template, tag, stop, lat, accepted, errors, interval):
    c = Conn(port)
    await c.login("engineer")
    _, _, page = await c.request("GET", "/submit")
    csrf = re.search(r'name="csrf" value="([0-9a-f]{64})"', page).group(1)
    n = 0
    while time.monotonic() < stop:
        doc = copy.deepcopy(template)
        doc["instrument"]["serial"] = f"LOAD-{tag}-{n:05d}"
        n += 1
        text = json.dumps(doc)
        b = "incalLoadBoundary"
        body = (f"--{b}\r\nContent-Disposition: form-data; name=\"csrf\"\r\n\r\n{csrf}\r\n"
                f"--{b}\r\nContent-Disposition: form-data; name=\"document\"; filename=\"r.json\"\r\n"
                f"Content-Type: application/json\r\n\r\n{text}\r\n--{b}--\r\n").encode()
        t = time.perf_counter()
        status, headers, _ = await c.request("POST", "/submit", body, f"multipart/form-data; boundary={b}")
        lat.append(time.perf_counter() - t)
        if status == 303:
            accepted.append(hashlib.sha256(text.encode()).hexdigest())
        else:
            errors.append(f"POST /submit: {status}")
        await asyncio.sleep(interval)
    c.close()


async def load(port, a, template):
    pages = ["/", "/?show=due"]
    for i in range(0, a.instruments, max(1, a.instruments // 10)):
        s = f"SN-{i:04d}"
        pages += [f"/instruments/{s}", f"/instruments/{s}/history?coefficient=K0", f"/records/{1 + i * a.records}"]
    pages.append("/events")
    stop = time.monotonic() + a.seconds
    read_lat, sub_lat, accepted, errors = [], [], [], []
    t0 = time.monotonic()
    by_page = {}
    tasks = [reader(port, pages[k % len(pages):] + pages[:k % len(pages)], stop, read_lat, errors, by_page)
             for k in range(a.readers)]
    tasks += [submitter(port, template, k, stop, sub_lat, accepted, errors, a.submit_interval) for k in range(a.submitters)]
    await asyncio.gather(*tasks)
    return read_lat, sub_lat, accepted, errors, time.monotonic() - t0, by_page


def line(name, lat, wall):
    ms = [x * 1000 for x in lat]
    return (f"  {name:<12} {len(lat):>7} done, {len(lat) / wall:7.1f}/s; latency ms: p50 {pct(ms, 50):6.1f}, "
            f"p95 {pct(ms, 95):6.1f}, p99 {pct(ms, 99):6.1f}, max {max(ms) if ms else float('nan'):6.1f}")


def one_store(a, incal, kind, d, docs, template):
    if kind == "sqlite":
        db = str(d / "load.db")
        pg = None
    else:
        pg = subprocess.run([str(Path(__file__).parent / "pg-test-server.sh"), str(os.getpid())],
                            capture_output=True, text=True, check=True)
        db = pg.stdout.strip()
    t = time.monotonic()
    fill_store(incal, db, docs, d)
    before = len(json.loads(run(incal, "record", "list", "--db", db, "--json"))["records"])
    print(f"{kind}: {before} records of {a.instruments} instruments stored in {time.monotonic() - t:.0f} s")
    port = free_port()
    server = subprocess.Popen([incal, "serve", "--db", db, "--listen", f"127.0.0.1:{port}"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(100):
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                time.sleep(0.1)
        cpu0 = time.process_time()
        read_lat, sub_lat, accepted, errors, wall, by_page = asyncio.run(load(port, a, template))
        client_cpu = time.process_time() - cpu0
        with open(f"/proc/{server.pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        server_cpu = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    finally:
        server.terminate()
        server.wait(timeout=30)
    print(f"{kind}: {a.readers} readers and {a.submitters} submitters for {wall:.0f} s "
          f"(CPU: server {server_cpu:.0f} s, this client {client_cpu:.0f} s, of {2 * wall:.0f} s on 2 cores)")
    print(line("page views", read_lat, wall))
    for page, lat in sorted(by_page.items()):
        print(line(f"  {page}", lat, wall))
    print(line("submissions", sub_lat, wall))
    ok = True
    if errors:
        print(f"  {len(errors)} errors, first: {errors[0]}")
        ok = False
    verify = run(incal, "record", "verify", "--db", db).strip()
    print(f"  record verify: {verify}")
    rows = json.loads(run(incal, "record", "list", "--db", db, "--json"))["records"]
    stored = {}
    for r in rows:
        stored[r["sha256"]] = stored.get(r["sha256"], 0) + 1
    lost = sum(1 for h in accepted if stored.get(h, 0) == 0)
    twice = sum(1 for h in accepted if stored.get(h, 0) > 1)
    count_ok = len(rows) == before + len(accepted)
    print(f"  accepted {len(accepted)}: lost {lost}, stored twice {twice}, "
          f"records {len(rows)} = {before} + {len(accepted)}: {'yes' if count_ok else 'NO'}")
    p99 = pct([x * 1000 for x in read_lat], 99)
    if not verify.startswith("ok") or lost or twice or not count_ok:
        ok = False
    if p99 > a.target_ms:
        print(f"  page views' p99 {p99:.1f} ms is over the target {a.target_ms} ms")
        ok = False
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--incal", default="target/release/incal")
    ap.add_argument("--store", choices=["sqlite", "postgres", "both"], default="both")
    ap.add_argument("--readers", type=int, default=50)
    ap.add_argument("--submitters", type=int, default=5)
    ap.add_argument("--submit-interval", type=float, default=1.0)
    ap.add_argument("--seconds", type=float, default=60)
    ap.add_argument("--instruments", type=int, default=100)
    ap.add_argument("--records", type=int, default=3)
    ap.add_argument("--target-ms", type=float, default=200)
    a = ap.parse_args()
    incal = os.path.abspath(a.incal)
    ok = True
    kinds = ["sqlite", "postgres"] if a.store == "both" else [a.store]
    for kind in kinds:
        with tempfile.TemporaryDirectory(prefix=f"incal-load-{kind}-") as tmp:
            d = Path(tmp)
            docs, template = make_documents(incal, d, a.instruments, a.records)
            ok &= one_store(a, incal, kind, d, docs, template)
    print("load test:", "passed" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
