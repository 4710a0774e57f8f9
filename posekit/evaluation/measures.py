"""The course's measures, each with one meaning: the glossary every lesson table and benchmark header uses.

Introduced in ``notebooks/01_fabrik.ipynb`` (where measures first appear) and rendered as ``docs/measures.md``
(:func:`glossary_markdown`). A table column that shows one of these quantities is headed by its ``header``
and means exactly the definition below: the frame the positions are compared in, what is averaged per pose,
how the cases are reduced (mean or median) and the unit. A quantity defined otherwise gets another name
(lesson 05's world-frame *mean joint error* is not MPJPE; the distance to the true pose is not
*naturalness*). ``tests/evaluation/test_measures.py`` checks the lessons' table headers against this list.

Also here: :func:`verdict_table`, the goal / measured / met table that ends each lesson's Discussion, and the one
yardstick a lesson reads an ordering of trained models against (:func:`run_spread`, :func:`ordering`): a gap smaller
than two runs of one setting differ is "level", whichever two methods it separates.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Measure", "MEASURES", "measure", "glossary_markdown", "verdict_table", "header_names", "run_spread",
           "ordering"]


@dataclass(frozen=True)
class Measure:
    """One measure of the course.

    Attributes
    ----------
    name : str
        What the prose calls it.
    headers : tuple of str
        Column headers that show it (the first is the canonical one).
    frame : str
        Where positions or rotations are compared.
    per_case : str
        What one case (one pose, one frame) contributes.
    reduction : str
        How the cases become one number in a table.
    unit : str
    code : str
        The function or key that computes it.
    lessons : str
        The lessons that report it.
    sources : tuple of str
        Substrings of the code that computes it: a lesson cell printing one of ``headers`` names one of them
        (the test's check that the column means this measure and not a look-alike).
    """

    name: str
    headers: tuple
    frame: str
    per_case: str
    reduction: str
    unit: str
    code: str
    lessons: str
    sources: tuple


MEASURES: tuple[Measure, ...] = (
    Measure("MPJPE", ("MPJPE mm", "MPJPE", "MPJPE (cm)"),
            "pelvis-relative: each pose's body joints minus its own pelvis",
            "mean over the body joints of the distance to the true pose's joint",
            "median over the cases", "mm",
            "posekit.data.metrics.mpjpe; PoseScores.mpjpe_mm, summary key mpjpe_mm_median",
            "01, 03, 04, 06; posekit bench ik, posekit bench all",
            ("mpjpe_mm_median", "mpjpe(", "score_poses", "studies[")),
    Measure("world joint error", ("world joint mm", "5-pt world joint mm", "val world joint mm"),
            "world frame, nothing aligned (the pelvis's own miss counts)",
            "mean over the body joints of the distance to the true pose's joint",
            "mean over the cases", "mm",
            "posekit.evaluation.effector_scores.scores()['mpjpe_mm']; ProtoRes training's val_mpjpe_mm",
            "05; posekit bench protores",
            ("scores(", "five_point_error", "val_mpjpe_mm", "5point_mpjpe_mm")),
    Measure("naturalness", ("natural mm", "natural"),
            "each pose in its own root frame (pelvis-relative, facing +Z)",
            "MPJPE to the nearest training pose (lower is more natural; the true poses' own value is the floor)",
            "median over the cases", "mm",
            "posekit.data.metrics.NaturalnessIndex; summary key natural_mm_median",
            "01, 03, 04, 06; posekit bench ik, posekit bench all",
            ("natural", "NaturalnessIndex")),
    Measure("effector error", ("effector mm", "effector deg", "worst effector (mm)"),
            "world frame",
            "the case's worst effector: distance for a position effector (mm), angle for a rotation or look-at "
            "effector (degrees)",
            "median over the cases", "mm or degrees",
            "posekit.evaluation.pose_scores.case_effector_errors; summary key effector_mm_median",
            "01, 03, 04, 06; posekit bench ik, posekit bench all",
            ("effector_mm", "effector_error", "score_poses", "bench_all", "eff_mm", "effector")),
    Measure("effector error per kind", ("pos mm", "rot deg", "look deg"),
            "world frame",
            "every effector of that kind, each on its own (not the case's worst)",
            "median over all effectors of that kind in all cases", "mm (position), degrees (rotation, look-at)",
            "posekit.evaluation.effector_scores.scores()['pos_mm', 'rot_deg', 'look_deg']",
            "05; posekit bench protores",
            ("scores(", "pos_mm", "tol_rows", "finish[")),
    Measure("convergence", ("converged",),
            "world frame",
            "1 when every effector of the case is within its tolerance (1 mm, 1 degree), else 0",
            "mean over the cases (a share)", "%",
            "IKResult.converged; summary key converged_fraction",
            "01, 03, 04, 05, 06; posekit bench ik, posekit bench all",
            ("converged", "met_share", "met")),
    Measure("L_ikd-L2", ("L_ikd-L2", "random L_ikd", "5-pt L_ikd"),
            "world frame, nothing aligned",
            "squared error of each coordinate of each body joint of the final (FK) pose",
            "mean over coordinates, body joints and cases", "1e-3 m^2 in tables",
            "posekit.evaluation.effector_scores.scores()['ikd_l2'] (Oreshkin et al. 2022's metric)",
            "05; posekit bench protores",
            ("ikd_l2",)),
    Measure("L_gpd-L2", ("L_gpd-L2",),
            "world frame, nothing aligned",
            "squared error of each coordinate of each body joint of the global position decoder's output",
            "mean over coordinates, body joints and cases", "1e-3 m^2 in tables",
            "posekit.evaluation.effector_scores.scores()['gpd_l2'] (the training loss's definition, all body joints; "
            "not the authors' benchmark metric, which scores the root position only)",
            "05; posekit bench protores",
            ("gpd_l2",)),
    Measure("L_loc-geo", ("L_loc-geo", "random L_loc", "5-pt L_loc"),
            "each joint's rotation relative to its parent (local)",
            "geodesic angle between the predicted and the true local rotation of each body joint",
            "mean over body joints and cases", "rad",
            "posekit.evaluation.effector_scores.scores()['loc_geo'] (Oreshkin et al. 2022's metric)",
            "05; posekit bench protores",
            ("loc_geo",)),
    Measure("joint error (rig)", ("joint error (cm)", "joint cm", "+ computed J, cm", "joint cm + Jacobian"),
            "world frame",
            "mean over the rig's joints of the distance between the rig's joints at the predicted controls and "
            "the wanted joints",
            "mean over the test frames", "cm",
            "posekit.invrig.lesson.Setup.joint_error",
            "02; posekit bench invrig",
            ("joint_error", "drift(")),
    Measure("ground-truth error (rig)", ("ground-truth error", "GT error", "control sd"),
            "rig controls",
            "mean over the controls of the absolute difference between predicted and true control, in that control's "
            "training standard deviations",
            "mean over the test frames", "training standard deviations",
            "posekit.invrig.lesson.Setup.ground_truth_error",
            "02; posekit bench invrig",
            ("ground_truth_error", "drift(")),
)


def measure(name: str) -> Measure:
    """The measure called ``name`` (case-insensitive), or a ValueError naming the known ones."""
    for m in MEASURES:
        if m.name.lower() == name.lower():
            return m
    raise ValueError(f"no measure {name!r}; the glossary has: {', '.join(m.name for m in MEASURES)}")


def header_names() -> dict[str, Measure]:
    """Every column header of the glossary, mapped to its measure."""
    return {h: m for m in MEASURES for h in m.headers}


def glossary_markdown() -> str:
    """The glossary as a Markdown table (``docs/measures.md`` and lesson 01 show it)."""
    lines = ["| measure | column header | frame | per case | reduction | unit |", "|---|---|---|---|---|---|"]
    for m in MEASURES:
        lines.append(f"| {m.name} | {', '.join(f'`{h}`' for h in m.headers)} | {m.frame} | {m.per_case} | "
                     f"{m.reduction} | {m.unit} |")
    return "\n".join(lines) + "\n"


# the page's figures and the source markers that say why they need no measured source (the syntax of
# tests/test_prose_numbers.py, docs/testing.md); the glossary shown in the lessons goes without them
_PAGE_MARKERS = {
    "(1 mm, 1 degree)": "(1 mm<!-- setting: an Effector's default tolerance -->, "
                        "1 degree<!-- setting: an Effector's default tolerance -->)",
    "1e-3 m^2 in tables": "1e-3<!-- definition: the tables' unit --> m^2 in tables",
}


def docs_page() -> str:
    """``docs/measures.md``: the glossary with where each measure is computed and reported."""
    out = ["# Measures: one meaning each", "",
           "Rendered from `posekit/evaluation/measures.py` (`python -m posekit.evaluation.measures > docs/measures.md`);",
           "`tests/evaluation/test_measures.py` checks that this page is what the module writes now.",
           "A column that shows one of these quantities is headed by one of its headers and means exactly this;",
           "a quantity defined otherwise has another name.", "", glossary_markdown(),
           "## Where each is computed and reported", ""]
    for m in MEASURES:
        out.append(f"- **{m.name}**: `{m.code}` — lessons {m.lessons}.")
    page = "\n".join(out) + "\n"
    for figure, marked in _PAGE_MARKERS.items():
        page = page.replace(figure, marked)
    return page


def run_spread(*pairs) -> float:
    """The run-to-run yardstick: the largest relative difference between two runs of one setting.

    Parameters
    ----------
    *pairs : (float, float)
        The same measure (lower is better, positive) from two training runs of one setting, one pair per place
        it was measured (each benchmark, say).

    Returns
    -------
    float
        ``max |a - b| / min(a, b)`` over the pairs: 0.25 when one run's error is 25 % above the other's.
    """
    if not pairs:
        raise ValueError("run_spread: expected at least one (run, run again) pair of values")
    out = 0.0
    for pair in pairs:
        a, b = (float(v) for v in pair)
        if not (a > 0 and b > 0):
            raise ValueError(f"run_spread: expected two positive errors of one setting, got {a!r} and {b!r}")
        out = max(out, abs(a - b) / min(a, b))
    return out


def ordering(a: float, b: float, spread: float) -> str:
    """How a method's error ``a`` stands against another's ``b`` (lower is better), read against ``spread``.

    Parameters
    ----------
    a, b : float
        The two methods' values of one measure on the same cases (positive).
    spread : float
        The yardstick (:func:`run_spread`): a relative gap at most this large is within the run-to-run noise.

    Returns
    -------
    str
        ``"ahead"`` when ``b`` exceeds ``a`` by more than ``spread`` (``b / a - 1 > spread``), ``"behind"`` when
        ``a`` exceeds ``b`` so, else ``"level"``. The same rule for every pair, learned or classical, so both sides
        of a comparison meet one yardstick.
    """
    a, b, spread = float(a), float(b), float(spread)
    if not (a > 0 and b > 0) or not spread >= 0:
        raise ValueError(f"ordering: expected two positive errors and a spread >= 0, got {a!r}, {b!r}, {spread!r}")
    return "ahead" if b / a - 1 > spread else "behind" if a / b - 1 > spread else "level"


def verdict_table(rows) -> str:
    """The goal / measured / verdict table that ends a lesson's Discussion.

    Parameters
    ----------
    rows : iterable of (goal, measured, met)
        ``goal`` as set in the lesson's Aim, ``measured`` the value shown (a string), ``met`` a bool, None
        when the lesson does not judge it (printed "not judged here"), or a string for a verdict that is
        neither (for example "not shown: within the noise" when the ordering holds by less than two runs of
        one setting differ); a string must not be empty.

    Returns
    -------
    str
        A fixed-width text table.
    """
    def verdict(ok):
        if isinstance(ok, str):
            if not ok.strip():
                raise ValueError("verdict_table: a verdict given as text must say something (got an empty string)")
            return ok
        return "not judged here" if ok is None else "met" if bool(ok) else "not met"

    rows = [(str(g), str(v), verdict(ok)) for g, v, ok in rows]
    if not rows:
        raise ValueError("verdict_table: expected at least one (goal, measured, met) row")
    wg = max(len("goal"), *(len(g) for g, _, _ in rows))
    wv = max(len("measured"), *(len(v) for _, v, _ in rows))
    lines = [f"{'goal':<{wg}}  {'measured':<{wv}}  verdict"]
    lines += [f"{g:<{wg}}  {v:<{wv}}  {ok}" for g, v, ok in rows]
    return "\n".join(lines)


if __name__ == "__main__":  # python -m posekit.evaluation.measures > docs/measures.md
    print(docs_page(), end="")
