#!/usr/bin/env python3
"""Citations of the model documentation (docs/model.md).

    python3 tools/model_citations.py check     # every citation names an existing section

Code comments, descriptions and documents cite the model documentation as "docs/model.md §N.M"
(or a range "§N.M-N.K"); `check` lists every citation whose section docs/model.md does not
have. Exit status 1 if one does not resolve."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "model.md"

NUMBER = r"\d+(?:\.\d+)?"
NEW = re.compile(rf"docs/model\.md\s+§\s*(?P<a>{NUMBER})(?:\s*[-–]\s*(?P<b>{NUMBER}))?")
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
    """Citations that name no section of docs/model.md."""
    known = sections()
    problems = []
    for path in files if files is not None else tracked_files():
        text = _read(path)
        if text is None:
            continue
        for lineno, line in enumerate(text.splitlines(), 1):
            for m in NEW.finditer(line):
                for key in ("a", "b"):
                    number = m.group(key)
                    if number and number not in known:
                        problems.append(
                            f"{_rel(path)}:{lineno}: §{number} is not a section: {line.strip()}"
                        )
    return problems


def main(argv: list[str]) -> int:
    if argv[1:] == ["check"]:
        problems = check()
        print("\n".join(problems) if problems else "every citation resolves")
        return 1 if problems else 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
