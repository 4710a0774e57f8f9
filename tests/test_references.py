"""One bibliography (``posekit.references``): every citation in a lesson, a README, the lesson metadata and the
library's docstrings is in it; every entry is cited; every lesson's reference list and every README reference
block is its rendering."""

import json
import re
from pathlib import Path

import pytest

from posekit.references import REFERENCES, find_citations, reference_blocks, render, render_list

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
READMES = [ROOT / "README.md", ROOT / "data_samples" / "README.md", ROOT / "data_samples" / "bandai_mini" / "README.md"]
SOURCES = sorted(p for p in (ROOT / "posekit").rglob("*") if p.suffix in (".py", ".md", ".j2")
                 and p.name != "references.py")


def _nb(path):
    return json.loads(path.read_text(encoding="utf-8"))


def _markdown(nb):
    return "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")


def _without_rendered(text):
    """Text minus the rendered entries (their venues and years are no author-year citations)."""
    for key in REFERENCES:
        text = text.replace(render(key), "")
    return text


def _texts():
    for p in NOTEBOOKS:
        nb = _nb(p)
        meta = nb["metadata"]["posekit"]
        yield p.name, _without_rendered(_markdown(nb))
        yield f"{p.name} metadata", " | ".join(str(meta.get(k) or "") for k in ("paper", "reading"))
    for p in READMES + SOURCES:
        yield str(p.relative_to(ROOT)), _without_rendered(p.read_text(encoding="utf-8"))


def _reference_list(nb):
    """The items of the lesson's **References** list (continuation lines joined)."""
    lines = "".join(nb["cells"][0]["source"]).split("\n")
    start = next(k for k, line in enumerate(lines) if line.startswith("**Reference"))
    items = []
    for line in lines[start + 1:]:
        if line.startswith("- "):
            items.append(line)
        elif line.startswith("  ") and items:
            items[-1] += " " + line.strip()
        else:
            break
    return items


def test_every_citation_is_in_the_bibliography():
    bad = [f"{where}: {text!r}" for where, t in _texts() for text, key in find_citations(t) if key is None]
    assert bad == [], "citations not in posekit.references (add the work there, or fix the cite):\n" + "\n".join(bad)


def test_the_citation_finder_catches_unknown_and_malformed_cites():
    found = dict(find_citations("as Victor & Meyer 2020 show; Aristidou 2011; Oreshkin et al. 2021; "
                                "Holden, Saito & Komura, TVCG 2017; Smith & Jones (2019)"))
    assert found == {"Victor & Meyer 2020": "victor2020", "Aristidou 2011": None, "Oreshkin et al. 2021": None,
                     "Holden, Saito & Komura, TVCG 2017": "holden2017", "Smith & Jones (2019": None}


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_lesson_reference_list_is_the_bibliography_rendered(path):
    nb = _nb(path)
    meta = nb["metadata"]["posekit"]
    keys = meta.get("references")
    assert keys, f"{path.name}: no 'references' keys in the notebook metadata"
    assert [k for k in keys if k not in REFERENCES] == [], f"{path.name}: unknown reference keys"
    for field in ("paper",):
        assert meta.get(field) is None or meta[field] in keys, f"{path.name}: metadata {field} is not a listed key"
    items = _reference_list(nb)
    assert len(items) == len(keys), f"{path.name}: {len(items)} items in the References list, {len(keys)} keys"
    for key, item in zip(keys, items):
        want = "- " + render(key)
        assert item == want or item.startswith(want + " — "), (
            f"{path.name}: reference {key!r} differs from the bibliography:\n  {item}\n  {want}")


@pytest.mark.parametrize("path", READMES[:2], ids=lambda p: str(p.relative_to(ROOT)))
def test_readme_reference_blocks_are_the_bibliography_rendered(path):
    blocks = reference_blocks(path.read_text(encoding="utf-8"))
    assert blocks, f"{path.name} has no <!-- references: ... --> block"
    for keys, body in blocks:
        assert body == render_list(keys), f"{path}: the block for {keys} differs from posekit.references"


def test_every_entry_is_cited():
    cited = set()
    for p in NOTEBOOKS:
        meta = _nb(p)["metadata"]["posekit"]
        cited |= set(meta.get("references", ())) | {meta.get("paper"), meta.get("reading")}
    for _, t in _texts():
        cited |= {key for _, key in find_citations(t)}
    for p in READMES:
        for keys, _ in reference_blocks(p.read_text(encoding="utf-8")):
            cited |= set(keys)
    assert sorted(set(REFERENCES) - cited) == [], "bibliography entries nothing cites"


def test_course_page_names_the_paper_from_the_bibliography():
    from posekit.course.lessons import lessons
    from posekit.references import long_cite

    for le in lessons():
        assert le.paper == (long_cite(le.paper_key) if le.paper_key else None)
        assert le.references and all(k in REFERENCES for k in le.references)


def test_no_stale_author_initials():
    """The lesson 03/04 papers are L. Victor's; the AE-GAN is C. Lazarou's."""
    text = "\n".join(t for _, t in _texts())
    assert re.findall(r"\b[BN]\. Victor|G\. Lazarou", text) == []
