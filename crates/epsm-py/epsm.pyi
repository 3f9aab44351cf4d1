"""epsm: a CPU differentiable renderer (extended path space manifolds and an
optimal-transport loss on RGBXY points), from Python.

Images are NumPy arrays (H, W, 3) in linear RGB, row 0 at the top. Parameter
values and gradients are in user units, keyed as in problem files
(docs/problem-format.md). Positions and motion are in film pixels, x right,
y down. The GIL is released while rendering, solving and matching.
"""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, "os.PathLike[str]"]
_Image = npt.NDArray[Union[np.float32, np.float64]]

class EpsmError(Exception):
    """An epsm error: str(e) is the message the CLI prints."""

    file: Optional[str]
    """The scene or problem file, when the error is located in one."""
    line: Optional[int]
    """1-based line in `file`, when known."""
    field: Optional[str]
    """The dotted field (`parameters[0].key`) or argument at fault."""
    message: str
    """What was wrong and what was expected."""

class Scene:
    """A scene read from a TOML, glTF 2.0 or Mitsuba 3 XML file, with the
    parameter values set on it since. Pickles as its path and values."""

    @property
    def path(self) -> str: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def values(self) -> List[Tuple[str, float]]:
        """The values set so far, in the order set."""
    def render(self, spp: Optional[int] = None, seed: Optional[int] = None) -> npt.NDArray[np.float32]:
        """Renders the scene: (H, W, 3) float32 linear RGB, bit for bit what
        `epsm render --spp --seed` writes to an EXR."""
    def set(self, key: str, value: float) -> None:
        """Sets parameter `key` (user units) and moves the scene."""
    def get(self, key: str) -> float:
        """The current value of parameter `key`: set, or the file's."""

def load_scene(path: _Path) -> Scene:
    """Reads a scene file (.toml, .gltf, .glb, .xml)."""

class Problem:
    """An optimization problem (docs/problem-format.md).

    `Problem(scene, params, target=None, **sections)` writes the problem
    file for you: `params` lists keys or `[[parameters]]` tables as dicts;
    `target` is an image at the scene's resolution, or None to render the
    true values; `sections` are further tables (`loss={...}`,
    `optimizer={...}`, `render={...}`). Pickles as its source.
    """

    def __init__(
        self,
        scene: Scene,
        params: Sequence[Union[str, Mapping[str, Any]]],
        target: Optional[_Image] = None,
        **sections: Mapping[str, Any],
    ) -> None: ...
    @property
    def keys(self) -> List[str]: ...
    @property
    def true_values(self) -> List[Optional[float]]: ...
    @property
    def iterations(self) -> int: ...
    @property
    def tolerance(self) -> Optional[float]: ...
    @property
    def text(self) -> Optional[str]:
        """The problem-file text of a problem built in Python."""
    @property
    def target(self) -> Optional[npt.NDArray[np.float32]]: ...
    def with_settings(self, **sections: Mapping[str, Any]) -> "Problem":
        """The same problem with tables replaced key by key
        (`optimizer={"seed": 2, "method": "drot"}`)."""

def load_problem(path: _Path) -> Problem:
    """Reads and checks a problem file; raises EpsmError naming the field."""

class Optimization:
    """A running optimization; `method` is "epsm", "drot" or "l2"."""

    def __init__(self, problem: Problem, method: Optional[str] = None) -> None: ...
    def step(self) -> Dict[str, Any]:
        """Runs one iteration; returns its run.csv row as a dict."""
    def gradient(self) -> npt.NDArray[np.float64]:
        """dL/dθ at the current θ (user units), without stepping."""
    def loss(self) -> float:
        """The loss gradient() differentiates, at the current θ."""
    theta: List[float]
    """The current parameter values; setting clamps to the bounds."""
    @property
    def param_error(self) -> Optional[float]:
        """RMS error of the current θ against the true values."""
    @property
    def keys(self) -> List[str]: ...
    @property
    def iteration(self) -> int: ...
    @property
    def done(self) -> bool: ...
    @property
    def rows(self) -> List[Dict[str, Any]]: ...
    @property
    def choices(self) -> List[Tuple[str, str, str]]: ...
    @property
    def best(self) -> Optional[Dict[str, Any]]:
        """The best judged θ: iteration, theta, judged_loss, param_error."""
    @property
    def target(self) -> npt.NDArray[np.float32]: ...
    def render(self, spp: int = 16) -> npt.NDArray[np.float32]: ...
    def checkpoint(self, path: _Path) -> None:
        """Writes the run's state and the problem's source (JSON)."""
    @staticmethod
    def restore(path: _Path) -> "Optimization":
        """The run a checkpoint() file holds, ready to continue."""

def motion_field(
    scene: Scene, key: str, spp: int = 16, seed: Optional[int] = None
) -> Tuple[npt.NDArray[np.float64], Dict[str, int]]:
    """dp/dθ of `key` per pixel, (H, W, 2) film pixels per user unit, and the
    differentiable paths counted by kind."""

def match(
    a: _Image,
    b: _Image,
    solver: str = "exact",
    lam: float = 1.0,
    blur: float = 0.01,
    resolution: Optional[Tuple[int, int]] = None,
) -> Dict[str, Any]:
    """OT matching of two images: loss, grad_points (H, W, 5), grad_rgb
    (H, W, 3), grad_xy (H, W, 2), assignment (exact) or None, targets
    (H, W, 5), stats."""

def read_image(path: _Path) -> npt.NDArray[np.float32]:
    """Reads an EXR (linear) or PNG (sRGB) file as linear RGB (H, W, 3)."""

def write_image(path: _Path, image: _Image) -> None:
    """Writes linear RGB as EXR (exact) or PNG (sRGB, 8-bit)."""
