"""The teaching notebooks (``notebooks/`` beside this module, README.md there): stored as
jupytext percent-format ``.py`` text, executed here top to bottom in a fresh Jupyter kernel
(nbclient, with a time limit) and written as an executed ``.ipynb`` and a self-contained
``.html`` (nbconvert) into an output folder (``zrp notebooks``: ``renders/notebooks/``).

The notebooks use the project's public API only (no name or module starting with ``_``;
tests/sim/test_notebooks.py checks it) and show their images and videos with mediapy.
Jupytext, nbclient, nbconvert and ipykernel are the ``notebooks`` extra: imported only when a
notebook is run.
"""

from __future__ import annotations

import math
import re
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from zrp.errors import InputError, ZRPError
from zrp.output import OutputDir

__all__ = ["NOTEBOOKS", "NOTEBOOK_DIR", "NotebookError", "NotebookRun", "execute_notebook",
           "kernel_transport", "mediapy_outputs", "notebook_file_names", "notebook_source",
           "run_notebooks"]

NOTEBOOK_DIR = Path(__file__).with_name("notebooks")

#: The notebooks in teaching order: (name, file stem, title, what a student learns).
NOTEBOOKS: tuple[tuple[str, str, str, str], ...] = (
    ("kinematics", "01_zrp_kinematics", "ZRP kinematics and the Euler-Rodrigues parameters",
     "Build the PUMA's pose from its zero reference position by hand, one joint rotation "
     "(Euler-Rodrigues parameters) at a time, and check it against the toolkit and MuJoCo."),
    ("circle", "02_paper_circle", "The paper's circle: one perturbed link, one perturbed axis",
     "Perturb one link and one joint axis by 0.1 %, watch the nominal and the perturbed arm "
     "side by side, and see why a link error only translates the tool."),
    ("tolerances", "03_monte_carlo_tolerances", "Monte Carlo and tolerance allocation",
     "Turn a tolerance stack into a distribution of robots, then let the allocation find the "
     "loosest tolerances that meet a P99 requirement."),
    ("gap", "04_sim_to_real_gap", "The sim-to-real gap: measure, diagnose, compensate",
     "Measure a simulated robot with hidden effects, let the diagnosis name them, compensate "
     "the commands and measure the gap shrink."),
    ("dynamic", "05_dynamic_gap", "The dynamic gap: where the model's torques miss",
     "Log a moving arm with hidden friction, rotor inertia and a payload, see where the "
     "model's inverse dynamics miss the torques, let the diagnosis name the effects, and "
     "re-simulate the corrected MJCF."),
)
NAMES = tuple(n[0] for n in NOTEBOOKS)
#: A notebook must run top to bottom within this many seconds (the laptop goal is two
#: minutes; the tests allow more on a loaded machine).
DEFAULT_TIMEOUT_S = 300.0


class NotebookError(ZRPError):
    """A notebook failed (a cell raised, or it overran its time limit); the message names
    the notebook and the cell."""


@dataclass(frozen=True)
class NotebookRun:
    """One executed notebook.

    Attributes:
        name, title: from :data:`NOTEBOOKS`.
        ipynb, html: the executed notebook and its HTML page.
        seconds: wall time of the execution (kernel start to last cell), s.
        mediapy_outputs: cell outputs written by mediapy (images and videos shown inline).
    """

    name: str
    title: str
    ipynb: Path
    html: Path
    seconds: float
    mediapy_outputs: int


def _check(names: Sequence[str] | None) -> list[str]:
    chosen = list(NAMES if names is None else names)
    bad = [n for n in chosen if n not in NAMES]
    if bad or not chosen:
        raise InputError(f"names: unknown notebook(s) {bad}; expected some of {NAMES}")
    return chosen


def _entry(name: str) -> tuple[str, str, str, str]:
    return next(n for n in NOTEBOOKS if n[0] == name)


def notebook_source(name: str) -> Path:
    """The jupytext percent-format source of notebook ``name``."""
    return NOTEBOOK_DIR / f"{_entry(_check([name])[0])[1]}.py"


def notebook_file_names(names: Sequence[str] | None = None) -> list[str]:
    """The files :func:`run_notebooks` writes for ``names`` (default all)."""
    return [f"{_entry(n)[1]}{ext}" for n in _check(names) for ext in (".ipynb", ".html")]


def mediapy_outputs(nb: Any) -> int:
    """Outputs of an executed notebook that mediapy wrote: its HTML tables of images
    (``show_image(s)``) and videos (``show_video(s)``)."""
    return sum(1 for cell in nb.cells if cell.cell_type == "code"
               for out in cell.get("outputs", [])
               if re.search(r'class="show_(images|videos)"',
                            str(out.get("data", {}).get("text/html", ""))))


def _html(nb: Any) -> str:
    """The executed notebook as one self-contained HTML page: the lab template without its
    CDN scripts (require.js, MathJax: the notebooks need neither, and offline they only
    raise console errors)."""
    from nbconvert import HTMLExporter

    body, _ = HTMLExporter(template_name="lab", require_js_url="", mathjax_url="",
                           embed_images=True).from_notebook_node(nb)
    return re.sub(r'<script src="">\s*</script>\s*', "", body)


def _require() -> None:
    """A named error when the ``notebooks`` extra is missing."""
    import importlib.util

    missing = [m for m in ("jupytext", "nbclient", "nbconvert", "nbformat", "ipykernel")
               if importlib.util.find_spec(m) is None]
    if missing:
        raise NotebookError(f"running the notebooks needs {', '.join(missing)}: pip install "
                            "'zrp-accuracy[notebooks]'")


def kernel_transport(folder: str | Path) -> Any:
    """The kernel manager's configuration (traitlets): the kernel talks to this process over
    local (IPC) sockets in ``folder``, not over unencrypted TCP on localhost, so ipykernel
    has no reason to warn "Kernel is running over TCP without encryption"; TCP (jupyter's
    default) where ZeroMQ has no IPC transport (Windows)."""
    import zmq
    from traitlets.config import Config

    config = Config()
    if zmq.has("ipc"):
        config.KernelManager.transport = "ipc"
        # absolute: jupyter's default ("kernel-ipc") is relative to each process's own working
        # folder, and the kernel's (the notebook's temporary folder) is not this one's
        config.KernelManager.ip = str(Path(folder).resolve() / "kernel")
    return config


def execute_notebook(source: str | Path, timeout_s: float = DEFAULT_TIMEOUT_S,
                     kernel: str = "python3") -> tuple[Any, float]:
    """Execute the jupytext percent-format file ``source`` top to bottom in a fresh kernel
    (working folder: a temporary one): the executed notebook (nbformat) and its wall time, s.

    Raises:
        NotebookError: a cell raised, or the run took longer than ``timeout_s`` (each cell
            gets what is left of it, and is interrupted when it overruns).
        InputError: no such file, or a non-positive ``timeout_s``.
    """
    if not timeout_s > 0:
        raise InputError(f"timeout_s: expected a positive time limit (s), got {timeout_s!r}")
    if not Path(source).is_file():
        raise InputError(f"source: no notebook text at {str(source)!r}")
    _require()
    import jupytext
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError, CellTimeoutError

    name = Path(source).stem
    nb = jupytext.read(source)
    nb.metadata["kernelspec"] = {"name": kernel, "display_name": kernel, "language": "python"}
    t0 = time.perf_counter()

    def left_s(cell: Any) -> int:   # the time limit is the whole notebook's
        return max(1, math.ceil(timeout_s - (time.perf_counter() - t0)))

    # a notebook's own files stay out of the way; the kernel's sockets get their own folder
    with tempfile.TemporaryDirectory() as work, tempfile.TemporaryDirectory() as sockets:
        client = NotebookClient(nb, timeout_func=left_s, kernel_name=kernel,
                                resources={"metadata": {"path": work}},
                                config=kernel_transport(sockets))
        # the kernel's own stderr (a message it could not send once interrupted at the time
        # limit: a ZMQError traceback) goes to a file, not the terminal: what ended the run
        # is said by the NotebookError below (issue 41 finding 7)
        try:
            with open(Path(sockets) / "kernel.err", "wb") as err:
                client.execute(stderr=err)
        except CellTimeoutError as exc:
            raise NotebookError(f"notebook {name}: ran over the time limit of {timeout_s:g} s "
                                "(the cell running then was interrupted)") from exc
        except CellExecutionError as exc:
            raise NotebookError(f"notebook {name}: a cell failed:\n{exc}") from exc
    seconds = time.perf_counter() - t0
    if seconds > timeout_s:
        raise NotebookError(f"notebook {name}: ran {seconds:.0f} s, over the time limit of "
                            f"{timeout_s:g} s")
    return nb, seconds


def run_notebooks(out: OutputDir, names: Sequence[str] | None = None, *,
                  timeout_s: float = DEFAULT_TIMEOUT_S, kernel: str = "python3"
                  ) -> list[NotebookRun]:
    """Execute the notebooks ``names`` (default all, in teaching order) into the entered
    folder ``out``: ``<stem>.ipynb`` (executed) and ``<stem>.html`` for each.

    Raises:
        NotebookError: a cell raised or the notebook ran longer than ``timeout_s``.
        InputError: an unknown name, or a non-positive ``timeout_s``.
    """
    if not timeout_s > 0:
        raise InputError(f"timeout_s: expected a positive time limit (s), got {timeout_s!r}")
    _require()
    import nbformat

    runs = []
    for name in _check(names):
        _, stem, title, _ = _entry(name)
        nb, seconds = execute_notebook(notebook_source(name), timeout_s, kernel)
        ipynb = out.write_text(f"{stem}.ipynb", nbformat.writes(nb))
        html = out.write_text(f"{stem}.html", _html(nb))
        runs.append(NotebookRun(name, title, ipynb, html, seconds, mediapy_outputs(nb)))
    return runs
