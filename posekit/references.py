"""The one bibliography of posekit: every paper, dataset and book the lessons, the READMEs, the course page
and the docstrings cite, keyed by a short key.

A lesson names its references by key in its notebook metadata (``posekit.references``, and ``posekit.paper``
for the paper it reproduces); its **References** list is :func:`render` of those keys, one item each, an
optional note after " — ". In running text a work is cited author-year, :func:`cite`'s form
("Aristidou & Lasenby 2011", "Victor et al. 2021"; three authors may also be written out, "Holden, Saito &
Komura 2017"). ``tests/test_references.py`` checks all of it: no citation outside this table, no entry that
nothing cites, every lesson's list equal to its rendering.

>>> cite("aristidou2011")
'Aristidou & Lasenby 2011'
>>> render("lazarou2020")
'C. Lazarou. *Autoencoding Generative Adversarial Networks.* arXiv preprint, 2020. arXiv:2004.05472'
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["Reference", "REFERENCES", "cite", "cite_forms", "render", "render_list", "reference", "long_cite",
           "find_citations"]


@dataclass(frozen=True)
class Reference:
    """One work: its authors as printed ("L. Victor"), title, venue (with volume), year, and where to find it."""

    authors: tuple[str, ...]
    title: str
    venue: str
    year: int
    doi: str | None = None
    arxiv: str | None = None
    url: str | None = None
    et_al: bool = False
    """True when ``authors`` lists only the first authors of a longer list."""
    abbrev: str | None = None
    """The venue's short name as running text may write it before the year ("TVCG 2017")."""
    note: str | None = None
    """What else a reader needs (the code's address, the conference it was presented at)."""

    @property
    def surnames(self) -> tuple[str, ...]:
        return tuple(a.split(". ")[-1].split(" ", 1)[-1] if ". " in a else a for a in self.authors)


REFERENCES: dict[str, Reference] = {
    "peng2018": Reference(
        ("X. B. Peng", "P. Abbeel", "S. Levine", "M. van de Panne"),
        "DeepMimic: Example-Guided Deep Reinforcement Learning of Physics-Based Character Skills",
        "ACM Transactions on Graphics 37(4) (SIGGRAPH)", 2018),
    "zhou2019": Reference(
        ("Y. Zhou", "C. Barnes", "J. Lu", "J. Yang", "H. Li"),
        "On the Continuity of Rotation Representations in Neural Networks", "CVPR", 2019),
    "shepperd1978": Reference(
        ("S. W. Shepperd",), "Quaternion from Rotation Matrix", "Journal of Guidance and Control 1(3)", 1978,
        doi="10.2514/3.55767b"),
    "aristidou2018": Reference(
        ("A. Aristidou", "J. Lasenby", "Y. Chrysanthou", "A. Shamir"),
        "Inverse Kinematics Techniques in Computer Graphics: A Survey", "Computer Graphics Forum", 2018),
    "kobayashi2023": Reference(
        ("M. Kobayashi",), "Motion Capture Dataset for Practical Use of AI-based Motion Editing and Stylization",
        "arXiv preprint", 2023, arxiv="2306.08861", et_al=True),
    "aristidou2011": Reference(
        ("A. Aristidou", "J. Lasenby"), "FABRIK: A fast, iterative solver for the Inverse Kinematics problem",
        "Graphical Models 73(5)", 2011),
    "wang1991": Reference(
        ("L.-C. T. Wang", "C. C. Chen"),
        "A combined optimization method for solving the inverse kinematics problem of mechanical manipulators",
        "IEEE Transactions on Robotics and Automation", 1991),
    "buss2004": Reference(
        ("S. R. Buss",),
        "Introduction to Inverse Kinematics with Jacobian Transpose, Pseudoinverse and Damped Least Squares methods",
        "course notes, University of California, San Diego", 2004),
    "nakamura1986": Reference(
        ("Y. Nakamura", "H. Hanafusa"),
        "Inverse Kinematic Solutions With Singularity Robustness for Robot Manipulator Control",
        "Journal of Dynamic Systems, Measurement, and Control 108(3)", 1986),
    "holden2016": Reference(
        ("D. Holden", "J. Saito", "T. Komura"), "A Deep Learning Framework for Character Motion Synthesis and Editing",
        "ACM Transactions on Graphics 35(4) (SIGGRAPH)", 2016),
    "holden2017": Reference(
        ("D. Holden", "J. Saito", "T. Komura"), "Learning Inverse Rig Mappings by Nonlinear Regression",
        "IEEE Transactions on Visualization and Computer Graphics 23(3)", 2017, doi="10.1109/TVCG.2016.2628036",
        abbrev="TVCG"),
    "victor2021": Reference(
        ("L. Victor", "A. Meyer", "S. Bouakaz"), "Learning-based pose edition for efficient and interactive design",
        "Computer Animation and Virtual Worlds 32(3–4) (CASA)", 2021, doi="10.1002/cav.2013", abbrev="CAVW",
        note="code: https://github.com/leonvictor/neural-pose-edition"),
    "victor2020": Reference(
        ("L. Victor", "A. Meyer"), "Character Pose Design in Latent Space For Animation Edition", "JFIG", 2020,
        url="https://hal.science/hal-03338910"),
    "aksan2019": Reference(
        ("E. Aksan", "M. Kaufmann", "O. Hilliges"), "Structured Prediction Helps 3D Human Motion Modelling",
        "ICCV", 2019),
    "lazarou2020": Reference(
        ("C. Lazarou",), "Autoencoding Generative Adversarial Networks", "arXiv preprint", 2020, arxiv="2004.05472"),
    "nocedal2006": Reference(
        ("J. Nocedal", "S. J. Wright"), "Numerical Optimization", "Springer, 2nd edition", 2006),
    "oreshkin2022": Reference(
        ("B. N. Oreshkin", "F. Bocquelet", "F. G. Harvey", "B. Raitt", "D. Laflamme"),
        "ProtoRes: Proto-Residual Network for Pose Authoring via Learned Inverse Kinematics",
        "ICLR", 2022, arxiv="2106.01981",
        note="code and the authors' result notebooks: https://github.com/Unity-Technologies/Labs, Projects/ProtoRes"),
    "oreshkin2020": Reference(
        ("B. N. Oreshkin",), "N-BEATS: Neural basis expansion analysis for interpretable time series forecasting",
        "ICLR", 2020, et_al=True),
    "vaswani2017": Reference(
        ("A. Vaswani",), "Attention Is All You Need", "NeurIPS", 2017, et_al=True),
    "shoemake1985": Reference(
        ("K. Shoemake",), "Animating Rotation with Quaternion Curves", "SIGGRAPH", 1985),
}


def reference(key: str) -> Reference:
    """The entry under ``key``; an unknown key is refused with the known ones named."""
    try:
        return REFERENCES[key]
    except KeyError:
        raise KeyError(f"no reference {key!r} in posekit.references (known: {', '.join(sorted(REFERENCES))})") from None


def cite(key: str) -> str:
    """The author-year form used in running text: one author "Lazarou 2020", two "Aristidou & Lasenby 2011",
    three or more "Victor et al. 2021"."""
    r = reference(key)
    s = r.surnames
    if r.et_al or len(s) > 2:
        who = f"{s[0]} et al."
    elif len(s) == 2:
        who = f"{s[0]} & {s[1]}"
    else:
        who = s[0]
    return f"{who} {r.year}"


def cite_forms(key: str) -> set[str]:
    """Every author-year form a text may use for ``key`` (:func:`cite`'s, and all three names written out)."""
    r = reference(key)
    forms = {cite(key)}
    if len(r.surnames) == 3 and not r.et_al:
        a, b, c = r.surnames
        forms.add(f"{a}, {b} & {c} {r.year}")
    return forms


def long_cite(key: str) -> str:
    """One line for a table cell (the course page): "Holden, Saito & Komura, Learning ..., IEEE TVCG ..., 2017"."""
    r = reference(key)
    who = cite(key).rsplit(" ", 1)[0]
    return f"{who}, {r.title}, {r.venue}, {r.year}"


def render(key: str) -> str:
    """The entry as a reference-list item (Markdown, without the leading "- ")."""
    r = reference(key)
    authors = ", ".join(r.authors) + (" et al" if r.et_al else "")
    text = f"{authors}. *{r.title}.* {r.venue}, {r.year}."
    if r.doi:
        text += f" doi:{r.doi}"
    elif r.arxiv:
        text += f" arXiv:{r.arxiv}"
    elif r.url:
        text += f" {r.url}"
    if r.note:
        text += f" ({r.note})"
    return text


def render_list(keys) -> str:
    """A Markdown list of :func:`render` for ``keys``, in their order."""
    return "\n".join(f"- {render(k)}" for k in keys)


_NAME = r"[A-Z][A-Za-z\u00c0-\u017f'\-]+"
_YEAR = r"\(?(?P<year>(?:19|20)\d\d)\b"
_VENUE = r"(?:,? (?P<venue>[A-Z][A-Za-z]+))?"
_MANY = re.compile(rf"\b(?P<who>{_NAME}(?: et al\.|(?:, {_NAME})* (?:&|and) {_NAME}))(?:'s)?{_VENUE},? {_YEAR}")
_ONE = re.compile(rf"\b(?P<who>{_NAME}){_VENUE},? {_YEAR}")


def _resolve(who: str, venue: str | None, year: str) -> str | None:
    for key, r in REFERENCES.items():
        if f"{who} {year}" in cite_forms(key) and (venue is None or venue in r.venue or venue == r.abbrev):
            return key
    return None


def find_citations(text: str) -> list[tuple[str, str | None]]:
    """Every author-year citation in ``text``, as ``(the text cited, its key or None when the bibliography
    has no such work)``. Read as citations: "A et al. 2020", "A & B 2020", "A, B & C 2020" (an optional venue
    such as "JFIG" or "TVCG" before the year, the year optionally in brackets), and "A 2020" where A is the
    first author of an entry (so a misspelt cite that drops the second author is caught too)."""
    found, spans = [], []
    for m in _MANY.finditer(text):
        found.append((m.start(), m.group(0), _resolve(m.group("who"), m.group("venue"), m.group("year"))))
        spans.append(m.span())
    firsts = {r.surnames[0] for r in REFERENCES.values()}
    for m in _ONE.finditer(text):
        if m.group("who") in firsts and not any(a <= m.start() < b for a, b in spans):
            found.append((m.start(), m.group(0), _resolve(m.group("who"), m.group("venue"), m.group("year"))))
    return [(t, k) for _, t, k in sorted(found)]


_BLOCK = re.compile(r"<!-- references: (?P<keys>[\w ]+) -->\n(?P<body>.*?)\n<!-- /references -->", re.S)


def reference_blocks(text: str) -> list[tuple[list[str], str]]:
    """The rendered reference lists of a Markdown file (a README): ``(keys, the list as written)`` for each
    ``<!-- references: key1 key2 -->`` ... ``<!-- /references -->`` block; the list must be
    :func:`render_list` of the keys."""
    return [(m.group("keys").split(), m.group("body")) for m in _BLOCK.finditer(text)]
