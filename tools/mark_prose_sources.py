"""Bind the figures of the lessons' markdown to their sources (``tests/test_prose_numbers.py``), and move markers.

A lesson's markdown holds words, maths and links only: each markdown cell keeps its figures' bindings in its
metadata (``cell.metadata["posekit"]["sources"]``, :func:`posekit.docs.prose.cell_bindings`). ``--migrate`` moves
the inline source markers (``28–29 mm<!-- out: ... -->``) of the named notebooks' markdown cells there, merged with
the bindings the metadata holds already; it touches only markdown cells' sources and metadata, never outputs, and
is idempotent, so it can be run again after a merge brings markers back:

    python tools/mark_prose_sources.py --migrate notebooks/0*.ipynb

After a merge with a branch that re-executed the notebooks (outputs only), keep its notebook and take this branch's
markdown cells (matched by cell id), then migrate what it may bring back inline:

    git checkout --theirs notebooks/05_protores.ipynb
    python tools/mark_prose_sources.py --markdown-from issue-64-markers --migrate notebooks/05_protores.ipynb

An author may also write a marker inline, as in a page of ``docs/``, and run ``--migrate``: it is the easiest way to
add a binding.

Without ``--migrate``, the tool proposes bindings for the unbound figures:

For each measured figure of a lesson's markdown that has no marker, it looks for the outputs of the notebook's code
cells (and the results files its code names) that show the same value in the same unit, nearest cell first, and
writes the marker that names it — ``<!-- out: "LABEL" -->``, ``<!-- out: "ROW" col "HEADER" -->`` or
``<!-- data: FILE PATH -->`` — after checking that the marker resolves to that very number. Only markdown cells are
edited; outputs are never touched. What it binds is a proposal to read: it prints every binding (figure, the
sentence, the output line it names) and every figure it could not bind, and ``--dry-run`` writes nothing. It works
on the markers inline (the metadata's bindings are put back in the text first) and moves them all into the
metadata when it writes.

    python tools/mark_prose_sources.py notebooks/05_protores.ipynb [--dry-run] [--exempt exempt.json]

``--exempt`` reads ``{"05": {"10 ms": "paper: Oreshkin et al. 2022 ..."}}``: figures as written, per lesson, that
get that exemption marker instead (goals, papers' figures, definitions, settings).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from posekit.docs import prose  # noqa: E402
from posekit.docs.prose import (_OUT_NUM, _UNIT_AFTER, Outputs, Source, SourceError, agrees,  # noqa: E402
                                blank_non_prose, family, figures, parse_markers, bind, resolve_data, _unit_of_header,
                                cell_bindings, inline_bindings, move_markers, set_cell_bindings)

RESULTS = ROOT / "data_samples" / "results"

# the old allow-list of tests/test_prose_numbers.py, as markers: (lesson, figure as written) -> marker body
EXEMPT = {
    ("03", "0.1 ms"): "goal: one solve (the Aim)", ("03", "5 µs"): "goal: per pose, batched (the Aim)",
    ("03", "3 cm"): "goal: effectors (the Aim)", ("04", "10 ms"): "goal: one solve (the Aim)",
    ("04", "2,000 solves per second"): "goal: batched, one thread (the Aim)",
    ("04", "2 cm"): "goal: the generator's pose, two targets (the Aim)",
    ("05", "20,000 poses per second"): "goal: a retired goal, shown above every network's ideal (section 6)",
    ("06", "3 ms"): "goal: per solve (the Aim)",
    ("04", "50 %"): "definition: a discriminator's accuracy when it cannot tell",
    ("04", "100 %"): "definition: a discriminator's accuracy when it has won",
    ("05", "45 seconds"): "setting: exercise 4's time budget (its instructor notes: seconds=45)",
    ("04", "20 seconds"): "setting: the live demo's time budget, seconds=20 in its code",
    ("05", "20 seconds"): "setting: the live demo's time budget, seconds=20 in its code",
    ("05", "20 m"): "setting: a target distance for the reader to try",
    ("05", "50 cm"): "setting: a target distance for the reader to try",
    ("05", "90°"): "setting: an angle for the reader to try",
    ("05", "1 mm"): "setting: the default tolerance of an Effector",
    ("01", "1 mm"): "setting: the convergence tolerance",
    ("01", "1 s"): "setting: the same-clip start's distance (posekit.data.cases)",
    ("04", "1 mm"): "setting: the optimisers' tolerance",
    ("06", "1 mm"): "setting: the sliders' step", ("06", "50 cm"): "setting: the sliders' range",
    ("06", "1 m"): "setting: where a look-at target starts",
    ("00", "90°"): "setting: an angle in an example", ("00", "0.5°"): "setting: an exercise's tolerance",
    ("01", "6.56 / 6.74 ms"): "paper: Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("03", "6.56 / 6.74 ms"): "paper: Victor et al. 2021, Table 1 (FABRIK, 2 / 5 effectors)",
    ("05", "10 ms"): "paper: Oreshkin et al. 2022, about 10 ms per pose in Unity",
    ("05", "33 hours"): "paper: Oreshkin et al. 2022, their training time on a GPU",
    ("03", "1 cm"): "setting: the std floor of the z-score (posekit.data.pose_vectors.STD_FLOOR)",
    ("03", "1 s"): "setting: training pairs at most 1 s apart (PAIR_MAX_S)",
    ("03", "5 s"): "setting: an exercise's suggested setting",
    ("03", "40 cm"): "setting: a suggested target for the reader to try",
    ("04", "40 cm"): "setting: a suggested target for the reader to try",
    ("03", "0.94 m"): "definition: the mini set's root helper point below the pelvis (a fact of the data)",
    ("03", "442 kB"): "paper: Victor et al. 2021, their model's size for two effectors",
    ("04", "0.1 %"): "setting: the optimisers' stopping rule", ("04", "0.05"): "setting: Adam's step size",
    ("04", "8 steps"): "setting: L-BFGS's memory",
    ("00", "30 fps"): "definition: the Bandai data's frame rate (a fact of the data)",
    ("01", "60°"): "setting: the near-extended step's threshold",
    ("06", "99%"): "goal: the lesson's Aim", ("06", "5%"): "goal: the lesson's Aim",
    ("05", "2,000 steps"): "setting: the studies' step count (posekit train protores-studies)",
}

# results files whose rows a lesson's prose reads (lesson 06 prints bench_all.md whole): bound by key there; no
# other lesson's figure is bound to a results file by the script (a value a file shares by chance would do)
DATA_FIRST = {"06": ("bench_all.json",)}

# read and decided: (lesson, the text that ends with the figure, once in the lesson's markdown) -> marker body
DECIDED = [
    ("00", "in 720 small steps of 0.5°", "setting: the demonstration's step"),
    ("01", "FABRIK reaches its targets (within 1 mm) in at least 95%", "goal: the lesson's Aim"),
    ("01", "sits at 97–99 %", "setting: the reach shares section 2's table places a head target at"),
    ("01", "is at ≥ 90 %", "setting: straighten_chain's ratio=0.9"),
    ("01", "lies at ≥ 90 %", "setting: straighten_chain's ratio=0.9"),
    ("01", "weighted as 0.1 m", "setting: DLS's weight of an angle, metres per radian"),
    ("01", "with `ratio` 0.5, 0.8, 0.95 and 0.999", "setting: ratios for the exercise to try"),
    ("01", "convergence (0.60",
     'out: "method set effector mm MPJPE mm bone mm converged iters" "fabrik-constrained 5point" col "converged"'),
    ("03", "for $k = 0.1$ and 1", "setting: a k of the study"),
    ("03", "for the shipped 0.01", "setting: the shipped solvers' k"),
    ("03", "The network alone misses by 7–29 mm", 'out: "start: same-clip" "neural-raw 2" col "effector mm"; '
     'out: "start: rest" "neural-raw 5" col "effector mm"'),
    ("03", "two hands within about 1 mm", 'out: "start: rest" "neural 2" col "effector mm"'),
    ("03", "leaves five effectors 17–23 mm", 'out: "start: rest" "neural 5" col "effector mm"; '
     'out: "start: other-clip" "neural 5" col "effector mm"'),
    ("03", "(worst 59 mm", 'out: "5 effectors worst case"'),
    ("03", "FABRIK's accuracy (0.1–0.3 mm", 'out: "start: rest" "neural-fabrik 2" col "effector mm"; '
     'out: "start: same-clip" "neural-fabrik 2" col "effector mm"'),
    ("03", "costs naturalness: 40–52 mm", 'out: "start: rest" "neural 2" col "natural mm"; '
     'out: "start: other-clip" "neural 2" col "natural mm"'),
    ("03", "after the backward pass against 33–44 mm", 'out: "start: rest" "neural-raw 2" col "natural mm"; '
     'out: "start: other-clip" "neural-raw 2" col "natural mm"'),
    ("03", "(five effectors: 24 / 18 / 24 mm", 'out: "full rest 5" col "neural"; out: "full same-clip 5" col '
     '"neural"; out: "full other-clip 5" col "neural"'),
    ("03", "another clip, against 29", 'out: "start: rest" "neural 5" col "MPJPE mm"'),
    ("03", "another clip, against 29 / 20", 'out: "start: same-clip" "neural 5" col "MPJPE mm"'),
    ("03", "another clip, against 29 / 20 / 25", 'out: "start: other-clip" "neural 5" col "MPJPE mm"'),
    ("03", "falls from 17.0 / 20.0 / 23.1 mm", 'out: "start: rest" "neural 5" col "effector mm"; out: "start: '
     'same-clip" "neural 5" col "effector mm"; out: "start: other-clip" "neural 5" col "effector mm"'),
    ("03", "on two hands (56 against 55 mm", 'out: "cross same-clip 2" col "neural"; out: "cross same-clip 2" '
     'col "FABRIK"'),
    ("03", "(five effectors 18.8 / 14.0 / 15.9 mm", 'out: "cross rest 5" col "eff."; out: "cross same-clip 5" '
     'col "eff."; out: "cross other-clip 5" col "eff."'),
    ("04", "(`posekit train aegan`: 9,000 steps", "setting: the shipped training's step count"),
    ("04", "against the neural solver's 68 / 54", 'out: "start: same-clip" "neural 2" col "MPJPE mm"'),
    ("04", "with five effectors 23 / 21 / 24 mm", 'out: "start: rest" "latent-opt 5" col "MPJPE mm"; out: "start: '
     'same-clip" "latent-opt 5" col "MPJPE mm"; out: "start: other-clip" "latent-opt 5" col "MPJPE mm"'),
    ("04", "24 mm against 28", 'out: "start: rest" "neural 5" col "MPJPE mm"'),
    ("04", "24 mm against 28 / 20", 'out: "start: same-clip" "neural 5" col "MPJPE mm"'),
    ("04", "24 mm against 28 / 20 / 24", 'out: "start: other-clip" "neural 5" col "MPJPE mm"'),
    ("04", "and FABRIK's 40", 'out: "start: rest" "fabrik 5" col "MPJPE mm"'),
    ("04", "and FABRIK's 40 / 33", 'out: "start: same-clip" "fabrik 5" col "MPJPE mm"'),
    ("04", "and FABRIK's 40 / 33 / 52", 'out: "start: other-clip" "fabrik 5" col "MPJPE mm"'),
    ("04", "It is never more than 4 mm", 'out: "latent-opt\'s full pose is never more than"'),
    ("04", "meets two targets to about 1 mm", 'out: "start: rest" "latent-opt-raw 2" col "effector mm"'),
    ("04", "and five to 5–8 mm", 'out: "start: same-clip" "latent-opt-raw 5" col "effector mm"; out: "start: rest" '
     '"latent-opt-raw 5" col "effector mm"'),
    ("04", "drift to 17–19 mm", 'out: "start: same-clip" "latent-opt 5" col "effector mm"; out: "start: '
     'other-clip" "latent-opt 5" col "effector mm"'),
    ("04", "of reconstruction (31 against 4 mm", 'out: "AE-GAN 32"; out: "autoencoder 64"'),
    ("04", "poses within 3 mm", 'out: "random codes >= 2x as natural as lesson 03\'s (beyond the floor)"'),
    ("04", "it rates real held-out poses 0.28",
     'out: "the pose discriminator calls held-out real poses real with median probability"'),
    ("04", "generated ones 0.02", 'out: "AE-GAN 32" col "real"'),
    ('05', 'in at most **1 ms',
     "goal: the lesson's Aim"),
    ('05', '**at least 50%',
     "goal: the lesson's Aim"),
    ('05', 'took 42,000 steps',
     'out: "steps, 2 processes," "masked-fcr"'),
    ('05', 'and trained for 2,000 steps',
     "setting: the studies' step count (posekit train protores-studies)"),
    ('05', 'The width runs take 2,000 steps',
     "setting: the studies' step count"),
    ('05', 'for 500 to 8,000 steps',
     "setting: the scaling study's step counts"),
    ('05', 'about 9x',
     'out: "the shipped run: 1.4e+13 parameter-poses ("'),
    ('05', 'with 9x',
     'out: "the shipped run: 1.4e+13 parameter-poses ("'),
    ('05', '(at 2,000 steps',
     "setting: the studies' step count"),
    ('05', 'at about 2e+03 core-hours',
     'out: "9.6e+02x the shipped run, about"'),
    ('05', "below FABRIK's 3.49",
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "fabrik" col "L_ikd-L2"'),
    ('05', 'where the line predicted 5.3',
     'out: "1.52e-3 measured," scale 1000'),
    ('05', 'The products alone fit the 1 ms',
     "goal: the lesson's Aim"),
    ('05', 'and its 159 MB',
     'out: "multiply-adds per pose (15x ours),"'),
    ('05', 'the caches: one pose\'s products alone, measured, take over 10 times',
     'out: "the paper\'s width: one pose\'s products alone take over"'),
    ('05', "paper's whole 10 ms per pose",
     'paper: Oreshkin et al. 2022, about 10 ms per pose in Unity on a GPU'),
    ('05', 'an orange marker 1 m',
     'setting: where a look-at target starts'),
    ('05', 'L2}$: ProtoRes 1.52',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "protores" col "L_ikd-L2"'),
    ('05', 'Masked-FCR 3.03',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "masked-fcr" col "L_ikd-L2"'),
    ('05', 'the Transformer 1.23',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "transformer" col "L_ikd-L2"'),
    ('05', "1.23 against FABRIK's 3.49",
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "fabrik" col "L_ikd-L2"'),
    ('05', "and DLS's 6.25",
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "dls" col "L_ikd-L2"'),
    ('05', '(FABRIK / ProtoRes 2.3',
     'out: "| classical / ProtoRes |" col "here"'),
    ('05', 'FinalIK / ProtoRes is 4.1–4.6',
     'paper: Oreshkin et al. 2022, Table 1 (FinalIK / ProtoRes)'),
    ('05', '(median 35.3 mm',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "protores" col "pos mm"'),
    ('05', 'median miss is 0.0 mm',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "fabrik" col "pos mm"'),
    ('05', 'in only 34%',
     'out: "5point benchmark, 1000 held-out cases" "converged" "fabrik" col "converged"'),
    ('05', '(world joint error 54 against 76 mm',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "protores" col "world joint mm"; out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "fabrik" col "world joint mm"'),
    ('05', 'world joint error 54 mm',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "protores" col "world joint mm"'),
    ('05', '(25.3 against 27.5 mm',
     'out: "random benchmark, 1000 held-out cases" "L_gpd-L2" "transformer" col "pos mm"; out: "random benchmark, 1000 held-out cases" "L_gpd-L2" "protores" col "pos mm"'),
    ('05', 'ahead of ProtoRes (1.23',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "transformer" col "L_ikd-L2"'),
    ('05', 'ahead of ProtoRes (1.23 against 1.52',
     'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "protores" col "L_ikd-L2"'),
    ('05', 'stay at 28–29 mm',
     'out: "Lambda pos mm rot deg look deg world joint mm" "0.7" col "pos mm"; out: "Lambda pos mm rot deg look deg world joint mm" "0.8" col "pos mm"'),
    ('05', 'to 36 mm at 0.9',
     'setting: a Λ of the table'),
    ('05', '(at most 5.498 mm',
     'out: "Lambda sigma (position)" "0.80"'),
    ('05', 'at 2,000 steps of width 128',
     "setting: the studies' step count"),
    ('05', '(+0.9',
     'out: "no GPD 10.36 ("'),
    ('05', 'and +0.7',
     'out: "fixed weights 10.10 ("'),
    ('05', '128 and 256 for 2,000 steps',
     "setting: the studies' step count"),
    ('05', '(17.50 and 10.7',
     'out: "core-min" "64 2000" col "5-pt L_ikd"'),
    ('05', 'At 2,000 steps',
     "setting: the studies' step count"),
    ('05', 'single pose fit the 1 ms',
     "goal: the lesson's Aim"),
    ('05', "At the paper's width one pose's products alone, measured, take over 10 times",
     'out: "the paper\'s width: one pose\'s products alone take over"'),
    ('05', '(at least 99%',
     "goal: the threshold the claims after section 9's table assert"),
    ('05', 'L2}$ 2.22',
     'out: "random benchmark, 1000 held-out cases" "converged" "protores+dls" col "L_ikd-L2"'),
    ('05', 'of all (1.19',
     'out: "5point benchmark, 1000 held-out cases" "converged" "protores+dls" col "L_ikd-L2"'),
    ('05', "of all (1.19 against FABRIK's 3.49",
     'out: "5point benchmark, 1000 held-out cases" "converged" "fabrik" col "L_ikd-L2"'),
    ('05', '0.302 against 0.264',
     'out: "5point benchmark, 1000 held-out cases" "converged" "protores" col "L_loc-geo"'),
    ('05', '0.302',
     'out: "5point benchmark, 1000 held-out cases" "converged" "protores+dls" col "L_loc-geo"'),
    ('05', '0.236 against 0.280',
     'out: "random benchmark, 1000 held-out cases" "converged" "protores" col "L_loc-geo"'),
    ('05', '0.236',
     'out: "random benchmark, 1000 held-out cases" "converged" "protores+dls" col "L_loc-geo"'),
    ('05', "against DLS's 3.40",
     'out: "random benchmark, 1000 held-out cases" "converged" "dls" col "L_ikd-L2"'),
    ('05', "and ProtoRes's 2.91",
     'out: "random benchmark, 1000 held-out cases" "converged" "protores" col "L_ikd-L2"'),
    ('05', "one pose's products alone fit the 1 ms",
     "goal: the lesson's Aim"),
    ('05', 'width take over 10 times',
     'out: "the paper\'s width: one pose\'s products alone take over"'),
    ("05", "(ProtoRes 1.52", 'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "protores" col "L_ikd-L2"'),
    ("05", "(ProtoRes 1.52 against 3.49", 'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "fabrik" col "L_ikd-L2"'),
    ("05", "(ProtoRes 1.52 against 3.49 and 6.25", 'out: "5point benchmark, 1000 held-out cases" "L_gpd-L2" "dls" col "L_ikd-L2"'),
    ('06', 'against 41.1',
     'data: bench_all.json rows[method=latent-opt+dls,effectors=2,start=rest].natural_mm_median'),
    ('06', 'against 41.1 and 39.7',
     'data: bench_all.json rows[method=neural+dls,effectors=2,start=rest].natural_mm_median'),
    ('06', 'are (47.3',
     'data: bench_all.json rows[method=neural+dls,effectors=2,start=other-clip].natural_mm_median'),
    ('06', 'are (47.3 and 50.1',
     'data: bench_all.json rows[method=latent-opt+dls,effectors=2,start=other-clip].natural_mm_median'),
    ('06', "against FABRIK's 59.3",
     'data: bench_all.json rows[method=fabrik,effectors=2,start=other-clip].natural_mm_median'),
    ('06', 'is the closest (18.0',
     'data: bench_all.json rows[method=latent-opt+dls,effectors=5,start=rest].mpjpe_mm_median'),
    ('06', 'is the closest (28.3',
     'data: bench_all.json rows[method=protores+dls,effectors=random,start=rest].mpjpe_mm_median'),
    ('06', '(natural 49.1 and 63.3 mm',
     'data: bench_all.json rows[method=fabrik,effectors=5,start=rest].natural_mm_median; data: bench_all.json rows[method=fabrik,effectors=5,start=other-clip].natural_mm_median'),
    ('06', "the true poses' own 35.7 mm",
     'data: bench_all.json natural_floor_mm_median.rest'),
    ('06', 'ProtoRes by 63.4 mm',
     'data: bench_all.json rows[method=protores,effectors=5,start=rest].effector_error_mm_median'),
    ('06', '(median) on set 5',
     "definition: an effector set's name"),
    ('06', 'and up to 183 mm',
     'out: "protores 23 frames; worst effector"'),
    ('06', 'in only 20%',
     'data: bench_all.json rows[method=fabrik,effectors=random,start=rest].converged_fraction'),
    ('06', 'from the rest pose too (18.0',
     'data: bench_all.json rows[method=latent-opt+dls,effectors=5,start=rest].mpjpe_mm_median'),
    ('06', 'every finish takes 2.49 ms per solve',
     'data: bench_all.json rows[method=latent-opt+dls,effectors=random,start=other-clip].latency_ms_median'),
    ('06', 'or less (0.690–2.49 ms',
     'data: bench_all.json rows[method=neural+dls,effectors=2,start=rest].latency_ms_median; data: bench_all.json rows[method=latent-opt+dls,effectors=random,start=other-clip].latency_ms_median'),
    ('06', 'behind FABRIK (75.8 mm',
     'data: bench_all.json rows[method=fabrik,effectors=2,start=rest].mpjpe_mm_median'),
    ('06', 'ProtoRes alone (108.3 mm',
     'data: bench_all.json rows[method=protores,effectors=2,start=rest].mpjpe_mm_median'),
    ('06', "the learned pose's in 48%",
     'data: bench_all.json rows[method=protores+dls,effectors=5,start=rest].learned_kept_fraction'),
    ('06', 'in every set (20.5',
     'data: bench_all.json rows[method=dls,effectors=5,start=rest].mpjpe_mm_median'),
    ('06', 'ignores the start: 44.1 mm',
     'data: bench_all.json rows[method=protores,effectors=5,start=rest].mpjpe_mm_median'),
    ('03', 'the network still wins (20',
     'out: "start: same-clip" "neural 5" col "MPJPE mm"'),
    ('05', 'ends level with it (60',
     'out: "188 ms per step): final validation world joint error"'),
    ('05', 'ends level with it (60 against 61 mm',
     'out: "365 ms per step): final validation world joint error"'),
    ('02', 'on the others 15%',
     'out: "of those with a control beyond the training range,"'),
    ("01", "a converged fraction of 1.00",
     'out: "method set effector mm MPJPE mm bone mm converged iters" "fabrik 5" col "converged"'),
]

# words before a figure that make it a setting, a goal or an example more often than a measurement: never bound
# by the script (listed for a reader to decide)
SETTING_CONTEXT = re.compile(r"(?i)(within|tolerance|ratio|at least|at most|≥|≤|<=|>=|goal|target of|step of|"
                             r"\bsay\b|\btry\b|e\.g\.|for example|budget|threshold|`[a-z_]+=)[^.]{0,25}$")


def _quote_ok(s: str) -> bool:
    return '"' not in s and "--" not in s and ";" not in s and s.strip() != ""


def _numbers(outputs: Outputs):
    """Every number of the outputs: (cell, text, line index, line, match, unit or None)."""
    for cell, text in outputs.cells:
        lines = text.split("\n")
        for li, line in enumerate(lines):
            for m in _OUT_NUM.finditer(line):
                after = line[m.end():]
                u = re.match(_UNIT_AFTER, after)
                if re.match(r"[A-Za-z_]", after) and not u:
                    continue
                unit = u.group("unit") if u else None
                header = _header_over(lines, li, m) if "|" not in line else _md_header(lines, li, m)
                if unit is None and header:
                    unit = _unit_of_header(header)
                yield cell, text, li, line, m, unit, header


def _header_over(lines, li, m):
    """The fixed-width column header over the number ``m`` of line ``li``: the run of words (single spaces) of the
    nearest line above with no decimal that overlaps the number's span."""
    for k in range(li - 1, max(-1, li - 40), -1):
        line = lines[k]
        if not line.strip() or re.search(r"%\|[#█ ]*\||\d+/s\]|it/s", line):
            continue                  # blank, or a progress bar
        if any(re.fullmatch(r"-?[\d,.]+%?", t) for t in re.sub(r"\([^)]*\)", "", line).split()):
            continue                  # a data line (a number of its own outside parentheses): a header has none
        # the header word over the number (overlapping it, else at most 2 characters beside it), with the words
        # before it when it alone is not unique on the line ("model kB" beside "solver kB")
        # a short run of words over the number ("frames 0-199", "world joint mm"), else one word
        for run in re.finditer(r"\S+(?: \S+)*", line):
            g = max(run.start() - m.end(), m.start() - run.end(), -1)
            if g < 0 and len(run.group(0).split()) <= 3 and re.search(r"[A-Za-z]", run.group(0)):
                return run.group(0)
        toks = list(re.finditer(r"\S+", line))
        best, gap = None, 3
        for k, t in enumerate(toks):
            g = max(t.start() - m.end(), m.start() - t.end(), -1)
            if g < gap and re.search(r"[A-Za-z%]", t.group(0)):
                best, gap = k, g
        if best is not None:
            k = best
            head = toks[k].group(0)
            while k > 0 and len(re.findall(rf"(?<!\S){re.escape(head)}(?!\S)", line)) > 1:
                k -= 1
                head = toks[k].group(0) + " " + head
            return head
        # a line of words that does not reach the number: keep looking up only through data lines
        if not re.search(r"\d", line):
            return None
    return None


def _md_header(lines, li, m):
    line = lines[li]
    pos = line[:m.start()].count("|") - 1
    for k in range(li - 1, -1, -1):
        if "|" not in lines[k]:
            return None
        cells = [c.strip() for c in lines[k].strip().strip("|").split("|")]
        if all(re.fullmatch(r":?-+:?", c) for c in cells if c):
            continue
        if k == 0 or "|" not in lines[k - 1] or all(re.fullmatch(r":?-+:?", c) for c in [
                c.strip() for c in lines[k + 1].strip().strip("|").split("|")] if c):
            return cells[pos] if 0 <= pos < len(cells) else None
    return None


def _unique_line_above(outputs: Outputs, text: str, li: int):
    """The nearest title-like line above ``li`` (this cell's output: words, at most one number) whose text occurs
    once in all the outputs."""
    lines = text.split("\n")
    for k in range(li - 1, -1, -1):
        t = " ".join(lines[k].split())
        if len(t) < 4 or not _quote_ok(t) or len(_OUT_NUM.findall(t)) > 1 or not re.search(r"[A-Za-z]{3}", t):
            continue
        src = Source("out", "", anchors=[t])
        try:
            outputs.resolve(src)
        except SourceError as e:
            if "times" in str(e):
                continue
            if "no number" not in str(e):
                continue
        return t
    return None


def _try(outputs, src, fig, value):
    try:
        v, unit, _ = outputs.resolve(src)
    except SourceError:
        return False
    return v == value and agrees(fig, v, unit)[0]


def _fmt(src: Source) -> str:
    body = " ".join(f'"{a}"' for a in src.anchors)
    if src.col:
        body += f' col "{src.col}"'
    if src.nth != 1:
        body += f" #{src.nth}"
    if src.unit:
        body += f" unit {src.unit}"
    if src.scale != 1:
        body += f" scale {src.scale:g}"
    return f"out: {body}"


def out_sources(outputs: Outputs, cell, text, li, line, m, header, fig, value, unit_hint=None):
    """Markers that name this number, most readable first, each checked to resolve to it."""
    nums_before = [n for n in _OUT_NUM.finditer(line[:m.start()])]
    label_start = nums_before[-1].end() if nums_before else 0
    label = " ".join(line[label_start:m.start()].split())
    label = re.split(r"[;,]", label)[-1].strip()
    label = re.sub(r"^[^A-Za-z(]*", "", label)
    first_cell = re.split(r"\s{2,}|\|", line.strip())[0].strip()
    between = " ".join(line[label_start:m.start()].split()).strip(" )")
    tries = []
    if len(label) >= 3 and _quote_ok(label):
        tries.append([label])
        # what comes before on the line, up to the number before: "worst frame ...: optimisation" then "GPR guess"
        prefix = line[:nums_before[-1].start()] if nums_before else ""
        prefix = " ".join(re.split(r"[;]", prefix)[-1].split()).strip(" ,:")
        if len(prefix) > 60:
            prefix = prefix[-60:].split(" ", 1)[-1]
        if len(prefix) >= 3 and _quote_ok(prefix):
            tries.append([prefix, label])
    if between and not label and _quote_ok(between) and first_cell and _quote_ok(first_cell) and \
            line.find(first_cell) + len(first_cell) <= label_start:
        tries.append([first_cell, between])
        # a longer label: from the line's start
        full = " ".join(line[:m.start()].split())
        if full != label and _quote_ok(full):
            tries.append([full])
    # a table row: its first cell, or its first cells, under the column's header
    cells = [c.strip() for c in re.split(r"\s{2,}|\|", line[:m.start()].strip()) if c.strip()]
    col = None
    rows = []
    if header and len(header) <= 30 and _quote_ok(header) and len(re.split(r"\s{2,}", line.strip())) >= 3:
        for k in range(1, len(cells) + 1):
            row = " ".join(" ".join(cells[:k]).split())
            if _quote_ok(row):
                rows.append(row)
        col = header
    tries = [[r] for r in rows] + tries
    ctx = _unique_line_above(outputs, text, li)
    out = []
    for anchors in tries:
        is_col = col is not None and anchors[0] in rows
        for a in (anchors, ([ctx] + anchors) if ctx and ctx not in anchors else None):
            if a is None:
                continue
            src = Source("out", "", anchors=list(a), col=col if is_col else None, unit=unit_hint)
            if _try(outputs, src, fig, value):
                out.append(src)
                break
        if out:
            break
    if not out and ctx:
        # the N-th number after the unique line above
        start = text.find(ctx) if ctx in text else None
        for n in range(1, 60):
            src = Source("out", "", anchors=[ctx], nth=n, unit=unit_hint)
            try:
                v, _, _ = outputs.resolve(src)
            except SourceError:
                break
            if _try(outputs, src, fig, value):
                out.append(src)
                break
        del start
    return out


def _results_named(nb) -> list[Path]:
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    helpers = {"protores_ablation.json": "studies_path", "protores_scaling.json": "scaling_path"}
    return [p for p in sorted(RESULTS.glob("*.json")) if p.stem in code or p.stem.rsplit("_", 1)[0] + "_{" in code
            or (p.name in helpers and helpers[p.name] in code)]


def _json_leaves(node, path=""):
    if isinstance(node, dict):
        for k, v in node.items():
            if re.fullmatch(r"[^.\[\]=,]+", str(k)):
                yield from _json_leaves(v, f"{path}.{k}" if path else str(k))
    elif isinstance(node, list):
        for i, e in enumerate(node):
            sel = f"[{i}]"
            if isinstance(e, dict):
                # the fewest identifying fields that pick this element alone: method, effectors, start first
                ids = {k: v for k, v in e.items() if isinstance(v, str) and len(v) < 40 and re.fullmatch(r"[^,\]=]+", v)}
                order = [k for k in ("method", "effectors", "start") if k in ids] + \
                    [k for k in ids if k not in ("method", "effectors", "start")]
                for n in range(1, len(order) + 1):
                    want = {k: ids[k] for k in order[:n]}
                    if sum(all(isinstance(o, dict) and o.get(k) == v for k, v in want.items()) for o in node) == 1:
                        sel = "[" + ",".join(f"{k}={v}" for k, v in want.items()) + "]"
                        break
            yield from _json_leaves(e, path + sel)
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield path, float(node)


def data_sources(files, fig):
    out = []
    for p in files:
        doc = json.loads(p.read_text(encoding="utf-8"))
        for path, v in _json_leaves(doc):
            src = Source("data", "", file=p.name, path=path)
            try:
                value, unit, _ = resolve_data(RESULTS, src)
            except SourceError:
                continue
            fam = family(unit)[0]
            if fig.unit and fam and fam != family(fig.unit)[0]:
                continue
            if not (fig.unit and fam):
                continue              # a key must name the prose's unit: a bare number matches too much
            if agrees(fig, value, unit)[0]:
                out.append(src)
    return out


def _plain(text: str):
    """``text`` without its source markers, and for each of its positions the position in ``text``."""
    keep, where = [], []
    pos = 0
    for mk in parse_markers(text):
        keep.append(text[pos:mk.start])
        where += range(pos, mk.start)
        pos = mk.end
    keep.append(text[pos:])
    where += range(pos, len(text) + 1)
    return "".join(keep), where


def insert_after(nb: dict, snippet: str, body: str) -> str | None:
    """Write ``<!-- body -->`` after ``snippet`` (once in the notebook's markdown, markers aside); None when done,
    else why not."""
    hits = []
    for c in nb["cells"]:
        if c["cell_type"] != "markdown":
            continue
        text = "".join(c["source"])
        plain, where = _plain(text)
        pattern = r"\s+".join(re.escape(w) for w in snippet.split())
        hits += [(c, text, where, m.end()) for m in re.finditer(pattern, plain)]
    if not re.search(r"\d[\d,.]*(?:\s?[\w/°%+-]+(?:\s(?:per|a)\s\w+)?)?$", snippet.strip()):
        return "the text does not end with its figure"
    if len(hits) != 1:
        return f"{len(hits)} places"
    c, text, where, end = hits[0]
    at = where[end - 1] + 1
    if text[at:].lstrip(" ").startswith("<!--"):
        return None               # marked already
    c["source"] = text[:at] + f"<!-- {body} -->" + text[at:]
    return None


def carry(old: dict, new: dict, width: int = 40) -> list[str]:
    """Carry the markers of an older version of a notebook (``old``) into ``new`` where the text before each is
    still there, once; returns the markers it could not place."""
    lost = []
    for c in old["cells"]:
        if c["cell_type"] != "markdown":
            continue
        text = "".join(c["source"])
        for mk in parse_markers(text):
            before, _ = _plain(text[:mk.start])
            snippet = before[-width:]
            why = insert_after(new, snippet, mk.raw[4:-3].strip())
            if why:
                lost.append(f"{mk.raw} after '{snippet}': {why}")
    return lost


def _row_score(src: Source, window: str) -> int:
    """How well the prose around a figure names a results row: its method (in backticks or not), its effector set
    and its start condition."""
    sel = dict(re.findall(r"(\w+)=([^,\]]+)", src.path))
    score = 0
    if sel.get("method") and re.search(rf"(?<![\w+-]){re.escape(sel['method'].lower())}(?![\w+-])", window):
        score += 4
    eff = {"2": ("two hands", "`2`", "2 effectors"), "5": ("five", "`5`", "5 effectors"),
           "random": ("random", "mixed kinds")}.get(sel.get("effectors", ""), ())
    score += any(e in window for e in eff)
    st = {"rest": ("rest",), "other-clip": ("other-clip", "another clip", "other clip")}.get(sel.get("start", ""), ())
    score += any(e in window for e in st)
    return score


def inline_all(nb: dict) -> list[str]:
    """Put every markdown cell's bindings back in its text as inline markers (in memory), for the proposing and
    carrying code, which reads markers inline; returns the bindings it could not place (stale)."""
    lost = []
    for i, c in enumerate(nb["cells"]):
        if c["cell_type"] != "markdown" or not cell_bindings(c):
            continue
        text, left = inline_bindings("".join(c["source"]), cell_bindings(c))
        c["source"] = text
        set_cell_bindings(c, left)
        lost += [f"cell {i}: stale binding {e!r}" for e in left]
    return lost


def migrate(nb: dict) -> dict[int, int]:
    """Move the inline source markers of every markdown cell of ``nb`` into its metadata (in memory), merged with the
    bindings there; only cells with a marker change. Returns ``{cell index: markers moved}``."""
    moved = {}
    for i, c in enumerate(nb["cells"]):
        if c["cell_type"] != "markdown":
            continue
        text = "".join(c["source"])
        n = len(parse_markers(text))
        if not n:
            continue
        try:
            plain, entries = move_markers(text, cell_bindings(c))
        except SourceError as e:
            raise SourceError(f"cell {i}: {e}") from None
        c["source"] = plain
        set_cell_bindings(c, entries)
        moved[i] = n
    return moved


def write_notebook(path: Path, nb: dict) -> None:
    """Write ``nb`` as nbformat does (indent 1, a final newline), as the lessons are committed."""
    path.write_text(nbformat.writes(nbformat.from_dict(nb)) + "\n", encoding="utf-8")


def migrate_file(path: Path, write: bool = True) -> dict[int, int]:
    """:func:`migrate` one notebook file; writes it only when a marker moved."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    moved = migrate(nb)
    if moved and write:
        write_notebook(path, nb)
    return moved


def take_markdown(nb: dict, other: dict) -> list[str]:
    """Give ``nb``'s markdown cells the text and metadata of ``other``'s cells of the same id (in memory), keeping
    ``nb``'s code cells and outputs: a merge of a branch that changed the lessons' words (and bindings) with one that
    re-executed them. Returns the ids of ``nb``'s markdown cells that ``other`` lacks (left as they are)."""
    theirs = {c.get("id"): c for c in other["cells"] if c["cell_type"] == "markdown" and c.get("id")}
    missing = []
    for c in nb["cells"]:
        if c["cell_type"] != "markdown":
            continue
        o = theirs.get(c.get("id"))
        if o is None:
            missing.append(str(c.get("id")))
            continue
        c["source"], c["metadata"] = o["source"], o["metadata"]
    return missing


def propose(path: Path, exempt: dict, write: bool) -> tuple[int, list]:
    nb = json.loads(path.read_text(encoding="utf-8"))
    for line in inline_all(nb):
        print(f"{path.name}: {line}")
    lesson = path.name[:2]
    for les, snippet, body in DECIDED:
        if les == lesson:
            why = insert_after(nb, snippet, body)
            if why:
                print(f"{path.name}: DECIDED '{snippet}' not placed: {why}")
    outputs = Outputs(nb)
    numbers = list(_numbers(outputs))
    files = _results_named(nb)
    unbound = []
    bound = 0
    for i, c in enumerate(nb["cells"]):
        if c["cell_type"] != "markdown":
            continue
        text = "".join(c["source"])
        blanked = blank_non_prose(text)
        pairs, _ = bind(blanked, figures(blanked), parse_markers(text))
        inserts = {}            # position -> [marker sources]
        groups = {}
        for fig, src, mk in pairs:
            if src is None and fig.required:
                groups.setdefault(fig.group, []).append(fig)
        for g, figs in groups.items():
            written = figs[-1].written
            if written in exempt.get(lesson, {}) or (lesson, written) in EXEMPT:
                inserts.setdefault(figs[-1].fig_end, []).append(exempt.get(lesson, {}).get(written)
                                                                 or EXEMPT[lesson, written])
                print(f"{path.name} cell {i}: {written!r} -> <!-- {inserts[figs[-1].fig_end][-1]} -->\n"
                      f"      | {_sentence(text, figs[-1].start)}")
                continue
            if SETTING_CONTEXT.search(blanked[max(0, figs[0].start - 60):figs[0].start]):
                for fig in figs:
                    unbound.append((i, fig.written, fig.num, "SETTING? " + _sentence(text, fig.start)))
                continue
            for fig in figs:
                found = None
                cands = []
                sentence = _sentence(text, fig.start)
                for cell, otext, li, line, m, unit, header in numbers:
                    value = float(m.group("num").replace(",", ""))
                    fam_s, fam_p = family(unit)[0], family(fig.unit)[0]
                    hint = None
                    if fam_p and fam_s and fam_s != fam_p:
                        continue
                    ok = agrees(fig, value, unit)[0]
                    if not ok and fam_p == "percent" and fam_s is None and agrees(fig, value, "share")[0]:
                        ok, hint = True, "share"
                    if not ok:
                        continue
                    same = 0 if (fam_p and fam_s) or not fam_p else 1
                    dist = (i - cell) if cell < i else (cell - i) + 2
                    nb_ = [n for n in _OUT_NUM.finditer(line[:m.start()])]
                    near = line[nb_[-1].end() if nb_ else 0:m.start()] + " " + re.split(r"\s{2,}", line.strip())[0]
                    words = {w.lower() for w in re.findall(r"[A-Za-z][\w+-]{2,}", near)}
                    said = sentence.lower()
                    overlap = -sum(1 for w in words if w in said)
                    cands.append((same, overlap, dist, cell, otext, li, line, m, header, value, hint))
                cands.sort(key=lambda t: (t[0], t[2], t[1]))
                # a results row the prose names (its method, with its effector set or start): bound to the file
                ds = data_sources([f for f in files if f.name in DATA_FIRST.get(lesson, ())], fig)
                window = text[max(0, fig.start - 160):fig.end + 40].lower()
                scored = sorted(((_row_score(d, window), k, d) for k, d in enumerate(ds)), key=lambda t: (-t[0], t[1]))
                if scored and scored[0][0] >= 5 and (len(scored) == 1 or scored[1][0] < scored[0][0]):
                    cands = []
                    found = (f"data: {scored[0][2].file} {scored[0][2].path}", "the prose names its row", len(ds))
                # a long report printed whole (lesson 06's bench_all.md): its numbers are bound to the results
                # file's keys instead, which name the row
                cands = [c for c in cands if len(c[4]) < 4000]
                for same, overlap, dist, cell, otext, li, line, m, header, value, hint in cands[:12]:
                    srcs = out_sources(outputs, cell, otext, li, line, m, header, fig, value, hint)
                    if srcs:
                        found = (_fmt(srcs[0]), f"cell {cell}: {line.strip()[:110]}", len(cands))
                        break
                if found is None:
                    ds = data_sources([f for f in files if f.name in DATA_FIRST.get(lesson, ())], fig)
                    window = text[max(0, fig.start - 160):fig.end + 40].lower()
                    scored = sorted(((_row_score(d, window), k, d) for k, d in enumerate(ds)), key=lambda t: (-t[0], t[1]))
                    if scored and scored[0][0] > 0 and (len(scored) == 1 or scored[1][0] < scored[0][0]):
                        d = scored[0][2]
                        found = (f"data: {d.file} {d.path}", f"{len(ds)} keys agree, best named", len(ds))
                if found is None:
                    unbound.append((i, fig.written, fig.num, _sentence(text, fig.start)))
                    continue
                inserts.setdefault(fig.end if fig is not figs[-1] else fig.fig_end, []).append(found[0])
                bound += 1
                print(f"{path.name} cell {i}: {fig.num!r} of {fig.written!r} [{found[2]} candidates] -> "
                      f"<!-- {found[0]} -->   ({found[1]})\n      | {_sentence(text, fig.start)}")
        if inserts and write:
            for pos in sorted(inserts, reverse=True):
                text = text[:pos] + "<!-- " + "; ".join(inserts[pos]) + " -->" + text[pos:]
            c["source"] = text
    if write:
        migrate(nb)
        write_notebook(path, nb)
    return bound, unbound


def _sentence(text, pos):
    """The words around ``pos``: what a reader checks a binding against."""
    return " ".join(text[max(0, pos - 90):pos].split()) + " ⟦" + " ".join(text[pos:pos + 50].split())


def _at_revision(rev: str, notebook) -> dict:
    """The notebook ``notebook`` as git revision ``rev`` holds it."""
    import subprocess

    rel = Path(notebook).resolve().relative_to(ROOT)
    return json.loads(subprocess.run(["git", "show", f"{rev}:{rel}"], cwd=ROOT, check=True, capture_output=True,
                                     text=True).stdout)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("notebooks", nargs="+")
    ap.add_argument("--dry-run", action="store_true")
    ap.add_argument("--migrate", action="store_true",
                    help="only move the markdown's inline source markers into the cells' metadata (idempotent)")
    ap.add_argument("--exempt", default=None)
    ap.add_argument("--markdown-from", default=None, metavar="REV",
                    help="first give the notebooks' markdown cells (text and metadata) those of git revision REV, "
                         "matched by cell id, keeping code cells and outputs (a merge with a re-execution)")
    ap.add_argument("--carry-from", default=None, metavar="REV",
                    help="first carry the markers of each notebook at git revision REV (after a merge took the "
                         "other side's notebook)")
    args = ap.parse_args(argv)
    exempt = json.loads(Path(args.exempt).read_text()) if args.exempt else {}
    if args.markdown_from:
        for nbp in args.notebooks:
            other = _at_revision(args.markdown_from, nbp)
            nb = json.loads(Path(nbp).read_text(encoding="utf-8"))
            missing = take_markdown(nb, other)
            print(f"{nbp}: markdown cells of {args.markdown_from}"
                  + (f"; not there, left as they are: {', '.join(missing)}" if missing else ""))
            if not args.dry_run:
                write_notebook(Path(nbp), nb)
        if not args.migrate:
            return 0
    if args.migrate:
        for nbp in args.notebooks:
            moved = migrate_file(Path(nbp), write=not args.dry_run)
            print(f"{nbp}: {sum(moved.values())} markers moved into the metadata of {len(moved)} cells"
                  + (f" ({', '.join(f'cell {i}: {n}' for i, n in moved.items())})" if moved else ""))
        return 0
    if args.carry_from:
        for nbp in args.notebooks:
            old = _at_revision(args.carry_from, nbp)
            new = json.loads(Path(nbp).read_text(encoding="utf-8"))
            inline_all(old)
            inline_all(new)
            lost = carry(old, new)
            for line in lost:
                print(f"{nbp}: NOT CARRIED {line}")
            if not args.dry_run:
                migrate(new)
                write_notebook(Path(nbp), new)
    for nbp in args.notebooks:
        bound, unbound = propose(Path(nbp), exempt, not args.dry_run)
        print(f"== {nbp}: {bound} bound, {len(unbound)} without a source")
        for i, w, n, s in unbound:
            print(f"   UNBOUND cell {i}: {n!r} of {w!r} | {s}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
