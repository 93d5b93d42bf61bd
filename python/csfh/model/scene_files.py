"""Reading scene and tolerance files: which file a command-line argument names, and its TOML.

Which file: an argument that is the name of a built-in scene (no ``/``, no ``.toml``) is that
scene, unless the working directory holds a file of that name too: then it is refused, naming
both (``./NAME`` is the file; the message gives the built-in scene's own path). A directory is
never a scene, so a directory named like a built-in scene does not hide it. Any other argument is
the path of a file.

The text: UTF-8 (a byte-order mark at the start is skipped, as TOML allows readers to), TOML
1.0. What Python's TOML reader cannot take (nesting deeper than its recursion limit, an integer
literal of more than 4300 digits) is one line naming the file, like a syntax error."""

from __future__ import annotations

import sys
import tomllib
from collections.abc import Collection
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import SceneError

BOM = "\ufeff"


def _is_bare(arg: str) -> bool:
    return "/" not in arg and "\\" not in arg and not arg.endswith(".toml")


def builtin_path(name: str) -> str:
    """Where the built-in scene `name` is (for messages)."""
    return str(resources.files("csfh").joinpath("scenes", f"{name}.toml"))


def locate(
    arg: str | Path, builtins: Collection[str], what: str = "scene", error: type = SceneError
) -> Path | None:
    """The file `arg` names, or None for the built-in scene of that name (module docstring);
    `error` (a SceneError type) naming the argument when it names neither (`what`: the kind of
    file asked for, scene or tolerance)."""
    text, path = str(arg), Path(arg)
    if _is_bare(text) and text in builtins:
        if path.exists() and not path.is_dir():
            raise error(
                f"{text!r} is both a built-in scene and the file ./{text} in this directory: "
                f"give ./{text} for the file, or {builtin_path(text)} for the built-in scene"
            )
        return None
    if path.suffix == ".toml" or path.exists():
        if path.is_dir():
            raise error(f"{path}: a directory, not a {what} file")
        if not path.is_file():
            raise error(f"{path}: no such {what} file")
        return path
    raise error(
        f"unknown scene {text!r}: use one of {', '.join(sorted(builtins))} or the path of a "
        f".toml {what} file"
    )


def read_text(path: Path, error: type = SceneError) -> str:
    """The UTF-8 text of a scene file, without a leading byte-order mark; `error` naming the
    file, and for text that is not UTF-8 the byte and its line."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise error(f"{path}: cannot be read ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise error(
            f"{path}: not UTF-8 text (TOML files are UTF-8): byte 0x{raw[exc.start]:02x} "
            f"at line {line}"
        ) from None
    return text.removeprefix(BOM)


def parse(text: str, source: str, error: type = SceneError) -> dict[str, Any]:
    """The TOML document; `error` naming `source` when it is not one Python can read."""
    try:
        return tomllib.loads(text.removeprefix(BOM))
    except tomllib.TOMLDecodeError as exc:
        reason = str(exc)
    except RecursionError:
        reason = "arrays or tables nested too deeply"
    except ValueError:  # int() of a literal beyond sys.get_int_max_str_digits()
        reason = f"an integer literal of more than {sys.get_int_max_str_digits()} digits"
    raise error(f"{source}: not valid TOML: {reason}")
