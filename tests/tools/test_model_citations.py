"""The model documentation (docs/model.md) as a citable reference: numbered sections and
equations, citations in the repository that resolve, nothing that points outside it."""

from __future__ import annotations

import itertools
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "model.md"
sys.path.insert(0, str(ROOT / "tools"))

import model_citations  # noqa: E402

SPEC_SECTIONS = (  # the numbering shared with the specification the document replaces
    "1.1 1.2 1.3 2.1 2.2 2.3 2.4 2.5 3 4.1 4.2 4.3 4.4 4.5 4.6 5.1 5.2 "
    "6.1 6.2 6.3 6.4 7.1 7.2 7.3 7.4 7.5 7.6 7.7 8 9"
).split()


def _git_files() -> list[Path]:
    try:
        return model_citations.tracked_files()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")


def test_sections_keep_the_specification_numbers() -> None:
    assert set(SPEC_SECTIONS) <= model_citations.sections()


def test_equation_numbers_are_unique_and_in_their_section() -> None:
    section, seen = "", []
    for line in DOC.read_text(encoding="utf-8").splitlines():
        m = re.match(r"##\s+(\d+)\.\s", line)
        if m:
            section = m.group(1)
        for tag in re.findall(r"\\tag\{([^}]*)\}", line):
            major, minor = tag.split(".")
            assert major == section, f"Eq. ({tag}) is in section {section}"
            seen.append((int(major), int(minor)))
    assert len(seen) > 50
    assert len(set(seen)) == len(seen), "duplicate equation number"
    assert seen == sorted(seen), "equations out of order"
    for (a, i), (b, j) in itertools.pairwise(seen):
        assert (b, j) == (a, i + 1) or (b > a and j == 1), f"gap after Eq. ({a}.{i})"


def test_every_citation_resolves() -> None:
    problems = model_citations.check(_git_files())
    assert not problems, "\n".join(problems)


def test_a_wrong_citation_is_found(tmp_path: Path) -> None:
    bad = tmp_path / "x.c"
    cite = "docs/model.md " + "\u00a7"  # assembled, so that the check of this file misses it
    bad.write_text(f"/* {cite}4.9, {cite}41.2, {cite}4.6, {cite}7.4-7.9 */\n", encoding="utf-8")
    problems = model_citations.check([bad])
    assert len(problems) == 3
    numbers = {p.split(" is not")[0].split(": ")[-1] for p in problems}
    assert numbers == {"\u00a74.9", "\u00a741.2", "\u00a77.9"}


def test_nothing_points_outside_the_repository() -> None:
    # the specification and the paper the model was first written from live outside it
    outside = re.compile(r"\.\./shared|/work/shared|shared/seed|" + "PHY" + "SICS")
    hits = []
    for path in _git_files():
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        if path.name == Path(__file__).name:
            continue
        for lineno, line in enumerate(text.splitlines(), 1):
            if outside.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{lineno}: {line.strip()}")
    assert not hits, "\n".join(hits)
