"""Measure a class on one hub: per-student memory and times for each lesson (00-06) and the studio with 1, 2, 4 ...
students at once.

    python deploy/jupyterhub/measure_class.py --students 1 --lessons 00,01,02,03,04,05,06 \
        --out deploy/jupyterhub/class_sizing.json
    python deploy/jupyterhub/measure_class.py --table deploy/jupyterhub/class_sizing.json    # docs/hub.md's table
    python deploy/jupyterhub/measure_class.py --values deploy/jupyterhub/class_sizing.json   # z2jh's resources

It starts a hub with the repository's configuration (jupyterhub_config.py: the trial login, the local spawner,
make lab's settings) in a temporary state folder, and for each lesson and each class size starts that many students'
servers at once through the hub's REST API (a fresh server per lesson, so that each lesson's peak is its own), then
has each student open their copy of the lesson (a notebook session in lessons/, as JupyterLab opens it) and run ALL
its code cells in order over the kernel websocket, all students at the same time; then every student opens the
studio at once (Voila renders their copy of studio.ipynb on their server, a second kernel): a student may keep it
open beside any lesson, and lesson 06 teaches it. Per student it records the server's start (request to ready), the
lesson's run (kernel start to its last cell done), the studio's page (request to the rendered page), and the memory
of the student's processes (the server and its kernels) after the lesson and after the studio, and the peak (the
sum of each process's VmHWM). No browser is involved: what a browser adds is on the student's machine. It does not
import posekit.
"""

from __future__ import annotations

import argparse
import asyncio
import datetime
import json
import math
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
import uuid
from pathlib import Path

from posekit.bench.browser import free_port

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
NOTEBOOKS = ROOT / "notebooks"
LESSON_FOLDER = "lessons"
"""The folder of each student's home that holds their copy of the lessons (jupyterhub_config.py copies them)."""
CELL_TIMEOUT_S = 1800
"""A lesson's cell that runs longer than this is reported as stuck (the measurement stops, it does not hang)."""
TOKEN = "posekit-measure-" + uuid.uuid4().hex
OVERLAY = """\
load_subconfig({config!r})
c.JupyterHub.services.append({{"name": "posekit-measure", "api_token": {token!r}}})
c.JupyterHub.load_roles.append({{"name": "posekit-measure", "services": ["posekit-measure"],
    "scopes": ["admin:users", "admin:servers", "list:users", "read:users", "access:servers"]}})
"""
TLJH_OVERHEAD_MB = 128
"""The Littlest JupyterHub's sizing rule: memory = concurrent users x per-user peak + 128 MB (the hub and proxy)."""
SIZES = (10, 20, 30, 50)
"""Class sizes the sizing table gives a machine's memory for."""


def _api(url, method, path, body=None, timeout=30):
    req = urllib.request.Request(f"{url}/hub/api{path}", method=method,
                                 data=None if body is None else json.dumps(body).encode(),
                                 headers={"Authorization": f"token {TOKEN}"})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            raw = r.read()
            return r.status, (json.loads(raw) if raw else None)
    except urllib.error.HTTPError as err:
        return err.code, None


def _server(url, user):
    status, info = _api(url, "GET", f"/users/{user}")
    return (info or {}).get("servers", {}).get("") if status == 200 else None


def lesson_names(spec, folder=NOTEBOOKS):
    """The lesson notebooks named by ``spec``, their numbers comma-separated ("00,01,06"), in that order.

    Raises ``SystemExit`` with a sentence naming the lessons there are when a number is not a lesson's or ``spec``
    names none."""
    lessons = {p.name[:2]: p.name for p in sorted(folder.glob("[0-9][0-9]_*.ipynb"))}
    wanted = [part.strip() for part in spec.split(",") if part.strip()]
    unknown = [w for w in wanted if w.zfill(2) not in lessons]
    if not wanted or unknown:
        raise SystemExit(f"--lessons {spec!r}: expected lesson numbers from {', '.join(lessons)}, comma-separated"
                         + (f" ({', '.join(unknown)} is not one)" if unknown else ""))
    return [lessons[w.zfill(2)] for w in dict.fromkeys(wanted)]


def lesson_code(path):
    """The source of every code cell of the notebook ``path``, in order (what Run All runs).

    Raises ``SystemExit`` naming the file when it is not a notebook or has no code cell."""
    try:
        nb = json.loads(Path(path).read_text())
        code = ["".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code"]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise SystemExit(f"{path}: expected a Jupyter notebook (JSON with code cells): {err}") from err
    if not any(src.strip() for src in code):
        raise SystemExit(f"{path}: expected a notebook with code cells, found none")
    return [src for src in code if src.strip()]


async def _run_lesson(url, user, lesson, code):
    """Open ``user``'s copy of ``lesson`` (a notebook session: its kernel runs in their lessons folder) and run
    ``code`` (cells) in it; returns the seconds it took."""
    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    headers = {"Authorization": f"token {TOKEN}"}
    t0 = time.perf_counter()
    status, session = await asyncio.to_thread(
        _user_api, url, user, "POST", "/api/sessions",
        {"path": f"{LESSON_FOLDER}/{lesson}", "name": lesson, "type": "notebook", "kernel": {"name": "python3"}})
    if status != 201:
        raise RuntimeError(f"{user}: could not open {lesson} with a kernel ({status})")
    ws_url = url.replace("http", "ws", 1) + f"/user/{user}/api/kernels/{session['kernel']['id']}/channels"
    conn = await websocket_connect(HTTPRequest(ws_url, headers=headers), max_message_size=1 << 30)
    for number, src in enumerate(code, 1):
        msg_id = uuid.uuid4().hex
        await conn.write_message(json.dumps({
            "header": {"msg_id": msg_id, "msg_type": "execute_request", "username": user, "session": msg_id,
                       "version": "5.3", "date": datetime.datetime.now(datetime.timezone.utc).isoformat()},
            "parent_header": {}, "metadata": {}, "channel": "shell",
            "content": {"code": src, "silent": False, "store_history": True, "user_expressions": {},
                        "allow_stdin": False, "stop_on_error": True}}))
        while True:
            try:
                raw = await asyncio.wait_for(conn.read_message(), CELL_TIMEOUT_S)
            except asyncio.TimeoutError:
                raise RuntimeError(f"{user}: {lesson}'s code cell {number} ran past {CELL_TIMEOUT_S} s") from None
            if raw is None:
                raise RuntimeError(f"{user}: the kernel's websocket closed")
            if isinstance(raw, bytes):
                continue
            msg = json.loads(raw)
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            if msg["msg_type"] == "error":
                raise RuntimeError(f"{user}: {lesson}'s code cell {number} failed: {msg['content']['ename']}: "
                                   f"{msg['content']['evalue']}")
            if msg["msg_type"] == "execute_reply":
                if msg["content"].get("status") != "ok":
                    raise RuntimeError(f"{user}: {lesson}'s code cell {number} ended with "
                                       f"{msg['content'].get('status')}")
                break
    conn.close()
    return time.perf_counter() - t0


def _user_api(url, user, method, path, body=None):
    req = urllib.request.Request(f"{url}/user/{user}{path}", method=method,
                                 data=None if body is None else json.dumps(body).encode(),
                                 headers={"Authorization": f"token {TOKEN}", "Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, json.loads(r.read() or b"null")
    except urllib.error.HTTPError as err:
        return err.code, None


def _open_studio(url, user):
    """Render ``user``'s copy of the studio with Voila on their server (the page a browser gets, its kernel run);
    returns the seconds it took."""
    t0 = time.perf_counter()
    req = urllib.request.Request(f"{url}/user/{user}/voila/render/lessons/studio.ipynb",
                                 headers={"Authorization": f"token {TOKEN}"})
    with urllib.request.urlopen(req, timeout=300) as r:
        page = r.read().decode()
    if "application/vnd.jupyter.widget-view+json" not in page:
        raise RuntimeError(f"{user}: the studio's page came without its app")
    return time.perf_counter() - t0


def _memory(hub_api, user):
    """(server RSS, kernels' RSS, peak of all) in MB for ``user``'s server process and its children (kernels); only
    a server of this hub (its API at ``hub_api``) counts, not another hub's student of the same name."""
    import psutil

    for proc in psutil.process_iter(["cmdline"]):
        try:
            cmd = proc.info["cmdline"] or []
            # the server itself, not the sandbox's unshare or init that carry its command line as arguments
            if not any(Path(part).name == "jupyterhub-singleuser" for part in cmd[:2]) or "sandbox.py" in " ".join(cmd[:2]):
                continue
            env = proc.environ()
            if env.get("JUPYTERHUB_USER") != user or env.get("JUPYTERHUB_API_URL", "").split("/hub/")[0] != hub_api:
                continue
            kids = proc.children(recursive=True)
            peak = sum(_hwm_kb(p.pid) for p in [proc, *kids]) / 1024
            return (proc.memory_info().rss / 2**20, sum(k.memory_info().rss for k in kids) / 2**20, peak)
        except psutil.Error:
            continue
    raise RuntimeError(f"no server process found for {user}")


def _hwm_kb(pid):
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    return 0


async def _class(url, hub_api, n, lesson, code):
    users = [f"student{i + 1}" for i in range(n)]

    async def one(user):
        t0 = time.perf_counter()
        status, _ = await asyncio.to_thread(_api, url, "POST", f"/users/{user}/server")
        if status not in (201, 202):
            raise RuntimeError(f"{user}: the hub refused to start the server ({status})")
        while not (await asyncio.to_thread(_server, url, user) or {}).get("ready"):
            if time.perf_counter() - t0 > 300:
                raise RuntimeError(f"{user}: the server did not start within 300 s")
            await asyncio.sleep(0.2)
        start_s = time.perf_counter() - t0
        lesson_s = await _run_lesson(url, user, lesson, code)
        return user, start_s, lesson_s

    for user in users:
        _api(url, "POST", "/users", {"usernames": [user]})
    try:
        done = await asyncio.gather(*(one(u) for u in users))
        with_lesson = {user: _memory(hub_api, user) for user, _, _ in done}
        # then every student opens the studio at once, from their own server (Voila's server extension)
        studio_s = await asyncio.gather(*(asyncio.to_thread(_open_studio, url, user) for user, _, _ in done))
        rows = []
        for (user, start_s, lesson_s), open_s in zip(done, studio_s):
            server_mb, kernels_mb, peak_mb = _memory(hub_api, user)
            rows.append({"student": user, "server_start_s": round(start_s, 2), "lesson_s": round(lesson_s, 2),
                         "studio_s": round(open_s, 2), "server_rss_mb": round(with_lesson[user][0], 1),
                         "kernel_rss_mb": round(with_lesson[user][1], 1),
                         "rss_mb": round(with_lesson[user][0] + with_lesson[user][1], 1),
                         "lesson_peak_mb": round(with_lesson[user][2], 1),
                         "studio_rss_mb": round(server_mb + kernels_mb, 1), "peak_mb": round(peak_mb, 1)})
    finally:  # every server stopped, so that the next lesson starts fresh ones (and their peaks are their own)
        for user in users:
            _api(url, "DELETE", f"/users/{user}/server")
        for user in users:
            t0 = time.perf_counter()
            while _server(url, user) is not None and time.perf_counter() - t0 < 120:
                time.sleep(0.5)
            _api(url, "DELETE", f"/users/{user}")
    return rows


def measure(sizes, lessons, out, note=""):
    """Measure ``lessons`` (notebook names) with each class size of ``sizes`` on a hub of this configuration; write
    the results file ``out`` (the command, the machine, the date, one run per lesson and size) and return it."""
    code = {lesson: lesson_code(NOTEBOOKS / lesson) for lesson in lessons}
    folder = Path(tempfile.mkdtemp(prefix="posekit-hub-measure-"))
    overlay = folder / "jupyterhub_measure_config.py"
    overlay.write_text(OVERLAY.format(config=str(HERE / "jupyterhub_config.py"), token=TOKEN))
    port, api_port = free_port(), free_port()
    env = dict(os.environ, POSEKIT_HUB_STATE=str(folder / "state"), POSEKIT_HUB_PORT=str(port),
               POSEKIT_HUB_API_PORT=str(api_port), POSEKIT_HUB_PROXY_API_PORT=str(free_port()),
               PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}")
    url, hub_api = f"http://127.0.0.1:{port}", f"http://127.0.0.1:{api_port}"
    with open(folder / "hub.log", "w") as log:
        hub = subprocess.Popen([str(Path(sys.executable).parent / "jupyterhub"), "-f", str(overlay)], cwd=folder,
                               env=env, stdout=log, stderr=subprocess.STDOUT)
        try:
            t0 = time.time()
            while "JupyterHub is now running" not in (folder / "hub.log").read_text(errors="replace"):
                if hub.poll() is not None or time.time() - t0 > 120:
                    raise SystemExit(f"the hub did not start; its log: {folder / 'hub.log'}")
                time.sleep(0.5)
            runs = []
            for lesson in lessons:
                for n in sizes:
                    rows = asyncio.run(_class(url, hub_api, n, lesson, code[lesson]))
                    runs.append({"lesson": lesson, "students": n, "per_student": rows})
                    print(f"{lesson}, {n} students: " + ", ".join(
                        f"start {r['server_start_s']:.1f} s, lesson {r['lesson_s']:.1f} s {r['rss_mb']:.0f} MB "
                        f"(peak {r['lesson_peak_mb']:.0f}), "
                        f"studio {r['studio_s']:.1f} s {r['studio_rss_mb']:.0f} MB (peak {r['peak_mb']:.0f})"
                        for r in rows), flush=True)
        finally:
            hub.terminate()
            try:
                hub.wait(timeout=60)
            except subprocess.TimeoutExpired:
                hub.kill()
    shutil.rmtree(folder, ignore_errors=True)
    result = {
        "command": shlex.join(["python", "deploy/jupyterhub/measure_class.py", *sys.argv[1:]]),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        # the operating system and architecture, not the kernel's build string (it names a host, not a machine)
        "machine": {"platform": f"{platform.system()} {platform.machine()}", "python": platform.python_version(),
                    "cpus": os.cpu_count(), "memory_gb": round(_total_memory() / 2**30, 1),
                    "note": note},
        "lessons": list(lessons), "cells": "every code cell of each lesson, in order; then the studio", "runs": runs,
    }
    result.update(worst(runs))
    Path(out).write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {out}")
    return result


def worst(runs) -> dict:
    """The largest per-student peak of ``runs`` (MB) and the lesson it was measured in: the figure a class is sized
    by (``per_student_peak_mb``, ``worst_lesson``)."""
    run, row = max(((run, r) for run in runs for r in run["per_student"]), key=lambda rr: rr[1]["peak_mb"])
    return {"per_student_peak_mb": row["peak_mb"], "worst_lesson": run["lesson"]}


def _total_memory():
    import psutil

    return psutil.virtual_memory().total


def _median(values):
    v = sorted(values)
    return (v[(len(v) - 1) // 2] + v[len(v) // 2]) / 2


def tljh_memory_gb(users, peak_mb):
    """TLJH's rule: users x per-user peak + 128 MB, in GB (1024 MB)."""
    return (users * peak_mb + TLJH_OVERHEAD_MB) / 1024


def table(result) -> str:
    """docs/hub.md's class-sizing tables (markdown), read from a results file of ``measure``."""
    lines = ["| lesson | students at once | server start, s | the whole lesson, s | the studio's page, s | "
             "memory with the lesson, MB | its peak, MB | with the lesson and the studio, MB | peak, MB |",
             "|---|---|---|---|---|---|---|---|---|"]
    for run in result["runs"]:
        rows = run["per_student"]
        times = [[r[k] for r in rows] for k in ("server_start_s", "lesson_s", "studio_s")]
        lines.append(f"| {run['lesson'].removesuffix('.ipynb')} | {run['students']} | " +
                     " | ".join(f"{_median(t):.1f} / {max(t):.1f}" for t in times) +
                     f" | {max(r['rss_mb'] for r in rows):.0f} | {max(r['lesson_peak_mb'] for r in rows):.0f} | "
                     f"{max(r['studio_rss_mb'] for r in rows):.0f} | "
                     f"{max(r['peak_mb'] for r in rows):.0f} |")
    lines += ["", "Times: median / slowest student; memory: the student using the most (their server and kernels), "
              "after the lesson, its peak then, after the studio too, and the peak of it all."]
    peak, lesson = result["per_student_peak_mb"], result["worst_lesson"].removesuffix(".ipynb")
    lines += ["", f"Memory a machine needs by TLJH's rule (students × {peak:.0f} MB, the peak of {lesson} with the "
              f"studio, + {TLJH_OVERHEAD_MB} MB):", "",
              "| students at once | " + " | ".join(str(n) for n in SIZES) + " |",
              "|---|" + "---|" * len(SIZES),
              "| memory, GB | " + " | ".join(f"{tljh_memory_gb(n, peak):.1f}" for n in SIZES) + " |"]
    return "\n".join(lines)


def z2jh_resources(result) -> dict:
    """zero-to-jupyterhub's ``singleuser`` memory and CPU from the measured peak of the worst lesson (with the studio
    open): the guarantee is that peak rounded up to 64 MB (what every student is sure to have), the limit twice that
    (the margin: room for the exercises, a second lesson's kernel left running; past it the kernel is killed), a
    quarter of a CPU guaranteed and one at most (a choice, not measured: the lessons' solvers run on one core at a
    time)."""
    guarantee = math.ceil(result["per_student_peak_mb"] / 64) * 64
    return {"memory": {"guarantee": f"{guarantee}M", "limit": f"{2 * guarantee}M"},
            "cpu": {"guarantee": 0.25, "limit": 1.0}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--students", default="1,2,4", help="class sizes to measure, comma-separated (default 1,2,4)")
    ap.add_argument("--lessons", default="00,01,02,03,04,05,06",
                    help="the lessons to run, their numbers comma-separated (default all: 00,01,02,03,04,05,06)")
    ap.add_argument("--out", default=str(HERE / "class_sizing.json"), help="the results file to write")
    ap.add_argument("--table", metavar="RESULTS", help="print docs/hub.md's tables from a results file and exit")
    ap.add_argument("--values", metavar="RESULTS", help="print z2jh's singleuser resources from a results file")
    ap.add_argument("--note", default="", help="a word on the machine kept in the results (e.g. what else ran)")
    args = ap.parse_args(argv)
    if args.table:
        print(table(json.loads(Path(args.table).read_text())))
    elif args.values:
        print(json.dumps(z2jh_resources(json.loads(Path(args.values).read_text())), indent=1))
    else:
        try:
            sizes = [int(n) for n in args.students.split(",")]
        except ValueError:
            raise SystemExit(f"--students {args.students!r}: expected class sizes, comma-separated (1,2,4)") from None
        measure(sizes, lesson_names(args.lessons), args.out, args.note)


if __name__ == "__main__":
    main()
