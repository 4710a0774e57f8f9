"""The documentation: the generated pages are what the code writes now, every results file carries its provenance,
the pages link to what exists, and the README stays a guide (short, no dates), losing nothing the old one said."""

import argparse
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from posekit import docs
from posekit.cli import build_parser, main
from posekit.docs import bench_page, cli_page

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "data_samples" / "results"
PAGES = sorted((ROOT / "docs").glob("*.md"))
GUIDES = [ROOT / "README.md", ROOT / "data_samples" / "README.md"] + PAGES
OTHER_ISSUES = {"measures.md", "nbgrader.md"}
"""Pages the index links to that other pieces of work write (the measures glossary, the nbgrader guide)."""


# --------------------------------------------------------------------------------------------- generated pages
def test_the_committed_generated_pages_are_what_the_code_writes_now():
    """Run as a user runs it, in a fresh process: in this one, other tests have imported plug-in modules out of
    the catalogue's order, and a registry lists its names in the order they were registered."""
    r = subprocess.run([sys.executable, "-m", "posekit", "docs", "build", "--check"], cwd=ROOT, capture_output=True,
                       text=True, env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=300)
    assert r.returncode == 0, r.stderr + "\n(run `posekit docs build` and commit the pages)"


def test_the_cli_page_has_every_subcommand_and_every_option():
    parser = build_parser()
    page = cli_page.markdown(parser)
    cmds = cli_page.commands(parser)
    assert len(cmds) > 30
    for words, p, _ in cmds[1:]:
        assert f"## `{' '.join(words)}`" in page, words
        for a in p._actions:
            for flag in a.option_strings:
                if flag not in ("-h", "--help"):
                    assert f"`{flag}" in page.split(f"## `{' '.join(words)}`")[1], (words, flag)


def test_the_cli_page_follows_a_changed_parser():
    parser = build_parser()
    before = cli_page.markdown(parser)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    p = sub.add_parser("teleport", help="a command added after the page was written")
    p.add_argument("--where", default="moon", help="the destination")
    after = cli_page.markdown(parser)
    assert after != before
    assert "## `posekit teleport`" in after and "| `--where WHERE` | the destination (default: moon) |" in after


def test_docs_build_check_reports_a_stale_page_and_build_fixes_it(tmp_path, capsys):
    assert main(["docs", "build", "--check", "--out", str(tmp_path)]) == 1
    assert "cli.md differs" in capsys.readouterr().err
    assert main(["docs", "build", "--out", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(docs.GENERATED)
    assert main(["docs", "build", "--check", "--out", str(tmp_path)]) == 0
    (tmp_path / "benchmarks.md").write_text("edited by hand\n")
    assert docs.stale(build_parser(), tmp_path) == ["benchmarks.md"]


# --------------------------------------------------------------------------------------------- results files
@pytest.mark.parametrize("path", sorted(RESULTS.glob("*.json")), ids=lambda p: p.name)
def test_every_results_file_carries_its_command_machine_and_date(path):
    d = json.loads(path.read_text())
    assert d["command"].startswith(("posekit ", "torchrun ")), d["command"]
    assert re.fullmatch(r"20\d\d-\d\d-\d\d", d["date"])
    m = d["machine"]
    assert m["platform"] and m["processor"] and m["cpu_count"] >= 1
    assert not re.search(r"\d+\.\d+\.\d+-", json.dumps(m)), "the kernel's build string names a host"


def test_the_shipped_report_names_no_kernel_build_string():
    for name in ("bench_all.md", "bench_all.json"):
        assert not re.search(r"Linux-\d", (RESULTS / name).read_text()), name


def test_the_benchmarks_page_shows_each_files_command_machine_and_date():
    page = bench_page.markdown()
    for path in sorted(RESULTS.glob("*.json")):
        d = json.loads(path.read_text())
        section = page.split(f"[`{path.name}`]")[0].rsplit("\n## ", 1)[1]
        assert f"`{d['command']}`" in section and d["date"] in section, path.name
        assert bench_page._machine(d["machine"]) in section


def _class_rows():
    return [{"sessions": 1, "session": 1, "updates": 100, "lost": 0, "p50_ms": 40.5, "p95_ms": 85.0, "max_ms": 99.1,
             "rss_mb": 236.2},
            {"class": "1 sessions", "sessions": 1, "kernels": 1, "rss_mb_total": 236.2, "lost": 0,
             "worst_p95_ms": 85.0, "kernels_after_cull": 0, "cull_s": 25.3},
            {"class": "2 sessions", "sessions": 2, "kernels": 2, "rss_mb_total": 473.9, "lost": 0,
             "worst_p95_ms": 157.4, "kernels_after_cull": 0, "cull_s": 23.1}]


def _rendered(page: str) -> str:
    """The page as a reader sees it: without the HTML comments (the source markers, posekit.docs.prose)."""
    return re.sub(r"<!--.*?-->", "", page, flags=re.S)


def test_the_class_sizing_table_appears_when_its_results_file_does(tmp_path):
    without = bench_page.markdown(tmp_path)
    assert bench_page.STUDIO_COMMAND in without and "No class-sizing results" in without
    (tmp_path / bench_page.STUDIO_SESSIONS).write_text(json.dumps(
        {"benchmark": "studio", "command": "posekit bench studio --sessions 1,2", "date": "2031-01-02",
         "machine": {"platform": "Linux x86_64", "processor": "Some CPU", "cpu_count": 8}, "rows": _class_rows()}))
    (tmp_path / "mine.json").write_text(json.dumps({"command": "posekit bench mine", "date": "2031-01-03",
                                                    "rows": [{"method": "x", "ms": 1.25}]}))
    marked = bench_page.markdown(tmp_path)
    page = _rendered(marked)
    assert "No class-sizing results" not in page
    assert "| 2 | 2 | 473.9 | 0 | 157.4 | 0 | 23.1 |" in page
    assert f"473.9<!-- data: {bench_page.STUDIO_SESSIONS} rows[2].rss_mb_total -->" in marked
    assert "`posekit bench studio --sessions 1,2`" in page and "2031-01-02" in page and "Some CPU, 8 CPUs" in page
    assert "## mine.json" in page and "| x | 1.25 |" in page  # a results file without a layout still shows


def test_bench_studio_out_writes_its_rows_with_command_machine_and_date(tmp_path, monkeypatch):
    from posekit.bench import studio
    from posekit.bench.plugin import get_benchmark

    monkeypatch.setattr(studio, "_measure", lambda args: _class_rows())
    out = tmp_path / "r" / bench_page.STUDIO_SESSIONS
    args = get_benchmark("studio").namespace(sessions="1,2", updates=50, out=str(out))
    assert studio._run(args) == _class_rows()
    d = json.loads(out.read_text())
    assert d["command"] == "posekit bench studio --sessions 1,2 --updates 50"
    assert re.fullmatch(r"20\d\d-\d\d-\d\d", d["date"]) and d["machine"]["cpu_count"] >= 1
    assert d["rows"] == _class_rows()
    assert "| 2 | 2 | 473.9 |" in _rendered(bench_page.markdown(out.parent))


# --------------------------------------------------------------------------------------------- the guides
def test_documented_commands_remake_what_is_shipped():
    """The bench all command the data README gives is the one recorded in the shipped report."""
    shipped = json.loads((RESULTS / "bench_all.json").read_text())["command"]
    text = (ROOT / "data_samples" / "README.md").read_text()
    documented = [c for c in re.findall(r"posekit bench all[^\n`#]*", text) if "--help" not in c]
    assert documented and all(c.strip() == shipped for c in documented), documented


def _slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    text = re.sub(r"[`*_]|\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(path: Path) -> set:
    text = re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.S)
    return {_slug(h) for h in re.findall(r"^#+ (.+)$", text, flags=re.M)}


@pytest.mark.parametrize("path", GUIDES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_between_the_pages_leads_somewhere(path):
    text = re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.S)
    bad = []
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        file, _, anchor = target.partition("#")
        dest = (path.parent / file).resolve() if file else path
        if dest.name in OTHER_ISSUES and not dest.exists():
            continue
        if not dest.exists():
            bad.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest):
            bad.append(f"{target}: no heading #{anchor}")
    assert bad == [], f"{path.relative_to(ROOT)}: broken links: {bad}"


def test_the_index_links_every_docs_page():
    index = (ROOT / "docs" / "index.md").read_text()
    linked = set(re.findall(r"\]\(([\w-]+\.md)", index))
    assert {p.name for p in PAGES} - {"index.md"} <= linked
    assert OTHER_ISSUES <= linked


def test_the_readme_is_a_front_page_not_a_log():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 150
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b", text), "a date in the README"
    for cmd in ("make lab", "make test", "make test-unit", "make studio"):
        assert f"{cmd} " in text, cmd
    assert "docs/index.md" in text and "CC BY-NC 4.0" in text and "MIT" in text
    for p in GUIDES:  # the generated pages give each results file's date, from the file
        if p.name not in docs.GENERATED:
            assert not re.search(r"\b20\d\d-\d\d-\d\d\b", p.read_text()), f"a date in {p.name}"


# What the README said before it became a front page: every command, setting and caveat a user could act on is in
# the README or a docs page (figures of single runs were left out on purpose: they live in results files).
KEPT = [
    "make lab", "make test", "make test-unit", "make test-portable", "make studio", "make slides", "make course",
    "make solutions", "LESSON=03", "make course-assets", "PYTEST_WORKERS=0", "posekit warm", "POSEKIT_NUMBA_CACHE",
    "~/.cache/posekit", "chromium-driver", "sudo", "npm", "torch 2.2–2.13", "torch==2.13.0", "CPU-only",
    "git checkout -- notebooks/", "environment.yml", "NoDelayConnection", "news", "update check",
    "notebooks/_template.ipynb", "tests/test_notebook_shape.py", "tools/strip_widget_state.py",
    "nbval-ignore-output", "tools/test_portable.py --list", "NPY_DISABLE_CPU_FEATURES", "ATEN_CPU_CAPABILITY",
    "OpenBLAS", "key-figure", "slide-skip", "slide-notes", "posekit course mark", "--check",
    "posekit exercises solutions", "--no-execute", "--html", "posekit exercises list", "duration_min",
    "prerequisites", "posekit/conventions.py", "(x, y, z, w)", "column vectors", "faces +Z",
    "`(..., J, 3)`", "posekit/catalogue.py", "SolverInfo.data", "tests/ik/test_ik.py",
    "posekit.ik.effector_errors", "solve_batch", "look-at", "posekit data inspect", "posekit data convert",
    "posekit data build-sample", "build-sample bandai", "posekit data build-benchmark protores", "posekit bench fk",
    "posekit bench ik", "posekit bench invrig", "posekit bench ae-scale", "--protocol full|cross",
    "posekit bench protores", "posekit bench all", "posekit bench studio", "--sessions 1,2,4,8", "posekit train --list",
    "posekit train invrig", "posekit train ae-solvers", "posekit train ae-studies", "posekit train aegan", "--dense",
    "--arch masked-fcr", "protores-studies --scaling", "protores-studies --shipped", "register_benchmark",
    "--weights DIR", "use_weights", "POSEKIT_WEIGHTS_DIR", "STUDIO_DATA", "STUDIO_WEIGHTS", "STUDIO_SOLVERS",
    "STUDIO_POOL", "STUDIO_ANTIALIAS=0", "POSEKIT_ANTIALIAS=0", "--antialias", "localhost:8866", "Ctrl-C",
    "culled", "notebooks/studio.ipynb", "studio_exports/session-", "posekit/io/torch_file.py", "posekit/viz/voila",
    "Font Awesome", "JupyterHub", "The Littlest", "--device", "cuda:N", "torchrun --standalone --nproc-per-node 2",
    "--nproc-per-node 8", "--width 1024 --batch 2048 --steps 40000", "tests/learn/test_distributed.py",
    "DistributedDataParallel", "rank 0", "POSEKIT_DATA_DIR", "../shared/data", "bandai-namco-2-every4th",
    "load_bandai(1)", "load_bandai_mini()", "--scale", "scale=0.056444", "roles={", "with_roles", "`Frames:`",
    "holds out the end of every clip", "file:line", "exit status 2", ".venv/bin/posekit", "arXiv 2306.08861",
    "non-commercial", "weight trained on it is CC BY-NC 4.0 too", "Peng et al. 2018", "internet at run time",
]


def test_nothing_a_user_could_do_before_is_lost():
    text = "\n".join(p.read_text(encoding="utf-8") for p in GUIDES)
    missing = [k for k in KEPT if k not in text]
    assert missing == [], f"no longer in the README or docs: {missing}"
