"""What `csfh linearize` writes: linearization.json (A, B, C, D and the modes), linearization.npz
(the same arrays), linearization.md (the operating point, the eigenvalues, the natural
frequencies and damping ratios) and bode.png (the frequency response of one input to one
output)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ...output import output_set, write_bytes, write_json, write_text
from ...plotting import save, subplots
from .jacobian import check_names
from .modes import frequency_grid, frequency_response
from .result import Linearization

OUTPUT_SET = "linearize"
FILES = ("linearization.json", "linearization.npz", "linearization.md", "bode.png")
DEFAULT_INPUT = "F_ext[2]"
DEFAULT_OUTPUT = "body1.y"


def check_pair(lin: Linearization, input_name: str, output_name: str) -> tuple[int, int]:
    """The indices of the Bode plot's input and output; ParameterError naming a wrong one."""
    check_names(input_name, output_name)
    return lin.inputs.index(input_name), lin.outputs.index(output_name)


def npz_bytes(lin: Linearization) -> bytes:
    buffer = io.BytesIO()
    np.savez(
        buffer,
        A=lin.A,
        B=lin.B,
        C=lin.C,
        D=lin.D,
        operating_point=lin.operating_point,
        input_values=lin.input_values,
        eigenvalues=lin.eigenvalues,
        frequencies_hz=np.array(lin.frequencies_hz),
        damping_ratios=np.array(lin.damping_ratios),
        states=np.array(lin.states),
        inputs=np.array(lin.inputs),
        outputs=np.array(lin.outputs),
    )
    return buffer.getvalue()


def plot_bode(path: Path, lin: Linearization, input_name: str, output_name: str) -> Path:
    """Magnitude and phase of G(i 2 pi f) from the input to the output, the natural frequencies
    dotted."""
    i, o = check_pair(lin, input_name, output_name)
    f = frequency_grid(lin.modes)
    G = frequency_response(lin.A, lin.B[:, [i]], lin.C[[o], :], lin.D[[o]][:, [i]], f)
    fig, (ax_mag, ax_phase) = subplots(2, 1, figsize=(7.5, 6.0), sharex=True)
    with np.errstate(divide="ignore"):
        ax_mag.semilogx(f, 20 * np.log10(np.abs(G)), color="tab:blue")
    # in [-180, 180), a real negative G at -180: past an undamped resonance G is real, and its
    # angle would come out +180 or -180 by the sign of a round-off imaginary part
    angle = np.where(
        np.abs(G.imag) <= 1e-6 * np.abs(G), np.where(G.real < 0, -np.pi, 0.0), np.angle(G)
    )
    phase = (np.degrees(angle) + 180.0) % 360.0 - 180.0
    ax_phase.semilogx(f, phase, color="tab:blue")
    ax_phase.set_yticks([-180, -90, 0, 90, 180])
    for m in lin.modes:
        for ax in (ax_mag, ax_phase):
            ax.axvline(m.frequency_hz, color="0.6", linestyle=":", linewidth=1)
    unit_in = lin_unit(input_name)
    unit_out = lin_unit(output_name)
    ax_mag.set_ylabel(f"|G| [dB re 1 {unit_out}/{unit_in}]")
    ax_phase.set_ylabel("phase [deg]")
    ax_phase.set_xlabel("frequency [Hz]")
    ax_mag.set_title(
        f"{lin.scene}, {lin.model} at {lin.at} ({'contact' if lin.in_contact else 'flight'}): "
        f"{input_name} -> {output_name}",
        fontsize=10,
    )
    for ax in (ax_mag, ax_phase):
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return save(fig, path, dpi=110)


def lin_unit(name: str) -> str:
    """The unit of an FMU variable (- without one)."""
    from ...model import model_info

    return str(model_info.variables()[name].unit or "-")


def markdown(lin: Linearization, input_name: str, output_name: str) -> str:
    """linearization.md: the point, the Jacobian source, the modes and the eigenvalues."""
    lines = [
        f"# Linearization of {lin.scene} ({lin.model}) at {lin.at}",
        "",
        f"Contact mode: {'contact' if lin.in_contact else 'flight'}. Jacobians: {lin.jacobian}.",
        "",
        "| state | value | d/dt |",
        "|---|---|---|",
    ]
    lines += [
        f"| `{n}` | {v:.9g} | {d:.3g} |"
        for n, v, d in zip(lin.states, lin.operating_point, lin.state_derivatives, strict=True)
    ]
    if lin.equilibrium is not None:
        eq = lin.equilibrium
        lines += [
            "",
            f"Static equilibrium ({eq.mode}): Newton's method converged in {eq.iterations} "
            f"iterations, largest residual acceleration {eq.residual:.3g}; gap {eq.gap:.6g} m, "
            f"indentation {eq.indentation:.6g} m; stiffness rank {eq.rank} of 3.",
            "",
            *[f"* {a}" for a in eq.attempts],
        ]
    lines += ["", "## Oscillatory modes", ""]
    if lin.modes:
        lines += ["| mode | natural frequency [Hz] | damped frequency [Hz] | damping ratio |"]
        lines += ["|---|---|---|---|"]
        lines += [
            f"| {k} | {m.frequency_hz:.8g} | {m.damped_frequency_hz:.8g} | {m.damping_ratio:.4g} |"
            for k, m in enumerate(lin.modes, 1)
        ]
    else:
        lines += ["None: every eigenvalue is real."]
    lines += ["", "## Eigenvalues", "", "| re [1/s] | im [rad/s] |", "|---|---|"]
    lines += [f"| {z.real:.8g} | {z.imag:.8g} |" for z in lin.eigenvalues]
    lines += [
        "",
        f"![Bode plot from {input_name} to {output_name}](bode.png)",
        "",
        f"Bode plot: from `{input_name}` to `{output_name}`; the dotted lines are the natural "
        "frequencies.",
        "",
    ]
    return "\n".join(lines)


def write_linearization(
    lin: Linearization,
    out: Path,
    input_name: str = DEFAULT_INPUT,
    output_name: str = DEFAULT_OUTPUT,
) -> Path:
    """Write the four files into `out` as one output set; returns the JSON's path."""
    check_pair(lin, input_name, output_name)
    with output_set(out, OUTPUT_SET):
        path = write_json(out / "linearization.json", lin.to_json())
        write_bytes(out / "linearization.npz", npz_bytes(lin))
        write_text(out / "linearization.md", markdown(lin, input_name, output_name))
        plot_bode(out / "bode.png", lin, input_name, output_name)
    return path
