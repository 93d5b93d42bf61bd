#!/usr/bin/env python3
"""Citations of the model documentation (docs/model.md).

    python3 tools/model_citations.py check     # every citation names an existing section
    python3 tools/model_citations.py rewrite   # PHYSICS.md citations -> docs/model.md §N.M

docs/model.md keeps the section numbers 1-9 of the specification it replaces (PHYSICS.md), so
`rewrite` maps "PHYSICS.md 7.6", "PHYSICS.md section 9", "PHYSICS.md sections 3-4",
"PHYSICS 2.4", "PHYSICS.md 7.4-7.6" to "docs/model.md §7.6", "docs/model.md §9",
"docs/model.md §3-4", "docs/model.md §2.4", "docs/model.md §7.4-7.6" (same numbers), and a bare
"PHYSICS.md" to "docs/model.md". Lines that discuss the specification's own printed numbers
("PHYSICS.md prints/quotes ...", misprints) are not rewritten but listed for a manual edit:
docs/model.md prints the corrected values there. Exit status 1 if a citation does not resolve
(check) or lines need a manual edit (rewrite)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "model.md"

NUMBER = r"\d+(?:\.\d+)?"
# "PHYSICS.md 7.6", "PHYSICS.md section 9", "PHYSICS.md sections 3-4", "PHYSICS 2.4", "PHYSICS.md"
OLD = re.compile(
    rf"PHYSICS(?P<md>\.md)?(?:(?P<sp>\s+)(?:(?P<word>sections?|§)\s*)?"
    rf"(?P<a>{NUMBER})(?:(?P<dash>\s*[-–]\s*)(?P<b>{NUMBER}))?)?(?![\w.]*\w)"
)
NEW = re.compile(rf"docs/model\.md\s+§\s*(?P<a>{NUMBER})(?:\s*[-–]\s*(?P<b>{NUMBER}))?")
MANUAL = re.compile(
    r"PHYSICS(?:\.md)?(?:\s+[\d.]+)?\s+(?:prints|quotes|used|says)"
    r"|misprint|computed in PHYSICS|key finding"
)
SKIP_SUFFIXES = {".png", ".fmu", ".so", ".zip", ".pdf"}


def sections(doc: Path = DOC) -> set[str]:
    """Section numbers of the headings of docs/model.md ("0", "1", "1.1", ...)."""
    found = set()
    for line in doc.read_text(encoding="utf-8").splitlines():
        m = re.match(rf"#{{2,3}}\s+({NUMBER})\.?\s", line)
        if m:
            found.add(m.group(1))
    return found


def tracked_files() -> list[Path]:
    out = subprocess.run(
        ["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    files = []
    for name in out:
        path = ROOT / name
        if path.suffix in SKIP_SUFFIXES or not path.is_file() or path == Path(__file__).resolve():
            continue
        files.append(path)
    return files


def _rel(path: Path) -> Path:
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


def _read(path: Path) -> str | None:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        return None


def check(files: list[Path] | None = None) -> list[str]:
    """Citations (old or new form) that name no section of docs/model.md."""
    known = sections()
    problems = []
    for path in files if files is not None else tracked_files():
        text = _read(path)
        if text is None:
            continue
        for lineno, line in enumerate(text.splitlines(), 1):
            for pattern in (OLD, NEW):
                for m in pattern.finditer(line):
                    for key in ("a", "b"):
                        number = m.group(key)
                        if number and number not in known:
                            problems.append(
                                f"{_rel(path)}:{lineno}: §{number} is not a section: {line.strip()}"
                            )
    return problems


def _replacement(m: re.Match[str]) -> str:
    if m.group("a") is None:
        return "docs/model.md" if m.group("md") else m.group(0)  # a bare word is no citation
    cited = m.group("a") + (f"-{m.group('b')}" if m.group("b") else "")
    return f"docs/model.md §{cited}"


def rewrite(files: list[Path] | None = None) -> tuple[int, list[str]]:
    """Rewrite the old citations in place; returns (lines changed, lines left for a manual edit)."""
    changed, manual = 0, []
    for path in files if files is not None else tracked_files():
        if path == DOC:
            continue
        text = _read(path)
        if text is None or "PHYSICS" not in text:
            continue
        lines = text.splitlines(keepends=True)
        for i, line in enumerate(lines):
            if "PHYSICS" not in line:
                continue
            if MANUAL.search(line):
                manual.append(f"{_rel(path)}:{i + 1}: {line.strip()}")
                continue
            new = OLD.sub(_replacement, line)
            if new != line:
                lines[i] = new
                changed += 1
        path.write_text("".join(lines), encoding="utf-8")
    return changed, manual


def main(argv: list[str]) -> int:
    if argv[1:] == ["check"]:
        problems = check()
        print("\n".join(problems) if problems else "every citation resolves")
        return 1 if problems else 0
    if argv[1:] == ["rewrite"]:
        changed, manual = rewrite()
        print(f"rewrote {changed} lines")
        if manual:
            print("edit by hand (they discuss the specification's printed numbers):")
            print("\n".join(manual))
        return 1 if manual else 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
