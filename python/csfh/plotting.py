"""Figures: matplotlib figures drawn off-screen (never through pyplot, so no GUI backend is touched
and nothing stays open), one colour per model, with legends that name the models as the command
line does, saved through csfh.output."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from .output import save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MODEL_COLORS = {
    "LN_spheres": "tab:blue",
    "LN_cylinders": "tab:orange",
    "LN_ESDU": "tab:green",
    "HuntCrossley": "tab:purple",
    "Flores": "tab:brown",
    "Moreau": "tab:red",
}
"""The colour of each model (csfh.model.model_info.MODELS) in every figure."""


def model_style(model: str) -> dict[str, Any]:
    """Colour and legend label of a model: the label is the model's name (LN_spheres, ...)."""
    return {"color": MODEL_COLORS.get(model, "k"), "label": model}


def subplots(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float], **kwargs: Any) -> Any:
    """A new figure and its axes, as matplotlib.pyplot.subplots returns them (fig, axes)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def save(fig: Figure, path: Path, **savefig: Any) -> Path:
    """Write the figure (format from the file's suffix)."""
    return save_figure(fig, path, **savefig)
