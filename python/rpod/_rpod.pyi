"""Type stubs of the extension module ``rpod._rpod`` (re-exported by ``rpod``).

Observation passed to a law added with ``Simulation.add_controller`` (numpy ``float64`` arrays;
``world`` = the scene's world frame, ``hill`` = the target's Hill frame, x radial out,
y along-track, z orbit normal; velocities relative to a rotating frame are the derivatives seen
in that frame; angular velocities are inertial)::

    {
      "t_s": float, "step": int, "dt_s": float,
      "body": str, "target": str | None,
      "mass_kg": float, "inertia_kg_m2": (3, 3),
      "own": State, "target_state": State | None, "bodies": {name: State},
      "relative": {                        # with a target
          "world": Rel, "hill": Rel | None, "target_body": Rel,
          "dcm_world_from_hill": (3, 3) | None, "hill_rate_world_rad_s": (3,) | None,
          "mean_motion_rad_s": float,      # target orbit's mean motion (0 outside an orbit)
      } | None,
      "ports": {                           # ports given, or the docking mechanism's
          "chaser": Port, "target": Port,
          "rel_pos_m": (3,), "rel_vel_m_s": (3,),   # target port frame (x: its axis)
          "rel_quat_wxyz": (4,),           # chaser port frame -> target port frame
          "misalignment_rad": float,
      } | None,
      "measured": {"t_s", "delivered_s", "fresh", "frame", "pos_m", "vel_m_s",
                   "quat_wxyz", "omega_rad_s", "yaw_rad"} | None,   # with a sensor
      "docking": {"state", "magnet_on", "gap_m", "axial_error_m", "lateral_m",
                  "misalignment_deg"} | None,
      "guarantees": {name: margin},        # at the end of the previous step
    }
    State = {"pos_m", "vel_m_s", "quat_wxyz" (body -> world), "omega_rad_s" (world),
             "rate_body_rad_s", "gravity_m_s2"}
    Rel   = {"pos_m", "vel_m_s"}
    Port  = {"pos_m", "vel_m_s", "quat_wxyz" (port frame -> world), "axis"}

Command returned by the law (or None: no force, no torque)::

    {"force_n": 3 numbers, "torque_nm": 3 numbers,
     "frame": "world" | "body" | "hill" | "target_body",   # or force_frame / torque_frame
     "valves": [bool, ...],                 # thruster actuators
     "diagnostics": {column: float}}        # columns declared in add_controller
"""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, PathLike]
_Vec = Union[Sequence[float], npt.NDArray[np.float64]]

# Defined in ``rpod/_errors.py`` (shown as ``rpod.SceneError``, …; they pickle).
from ._errors import NumericError as NumericError
from ._errors import SceneError as SceneError
from ._errors import SimulationError as SimulationError

class Simulation:
    """One scene, stepped from Python (see the module docs of ``rpod``). Only the thread that
    created it may use it (any other raises ``SimulationError``)."""

    def __init__(
        self,
        scene: _Path,
        set: Optional[Dict[str, Union[str, float, int, bool]]] = None,
        out_dir: Optional[_Path] = None,
        record: bool = True,
    ) -> None: ...
    @property
    def t_s(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def name(self) -> str: ...
    @property
    def scene_file(self) -> str: ...
    @property
    def body_names(self) -> List[str]: ...
    def state(self, name: str) -> Dict[str, npt.NDArray[np.float64]]: ...
    def body_info(self, name: str) -> Dict[str, Any]:
        """``name``, ``role``, ``mass_kg``, ``inertia_kg_m2`` (3×3, body axes about the centre
        of mass), ``com_body_m``, ``bounding_radius_m``, ``ports`` ({name: {``pos_body_m``,
        ``axis_body``}})."""
    def hill_state(self, name: str) -> npt.NDArray[np.float64]: ...
    def port_relative(
        self, chaser: str, chaser_port: str, target: str, target_port: str
    ) -> Dict[str, Any]: ...
    def apply(
        self,
        name: str,
        force_n: Optional[_Vec] = None,
        torque_nm: Optional[_Vec] = None,
        frame: str = "world",
    ) -> None: ...
    def add_controller(
        self,
        func: Callable[[Dict[str, Any]], Optional[Dict[str, Any]]],
        body: str,
        period_s: float,
        target: Optional[str] = None,
        actuator: Optional[str] = None,
        sensor: Optional[str] = None,
        ports: Optional[Tuple[str, str]] = None,
        columns: Optional[List[str]] = None,
    ) -> int: ...
    def add_guarantee(
        self,
        func: Callable[[Dict[str, Any]], float],
        name: str,
        unit: str,
        rate_bound: Optional[float] = None,
    ) -> int:
        """A guarantee written in Python: ``func(view)`` returns the margin (≥ 0 held, < 0
        violated) in ``unit``; ``view`` = {``t_s``, ``bodies``: {name: {``pos_m``, ``vel_m_s``,
        ``quat_wxyz``, ``omega_rad_s``, ``rate_body_rad_s``}} (world frame), ``distances_m``:
        {``"a/b"``: full-geometry distance of each tracked pair}}. With ``rate_bound`` (a bound
        on |d margin/dt| in ``unit``/s that you guarantee) it is judged on every step interval;
        without, at the samples only (``judged: "samples only"``). Shown in ``monitor()``, the
        trajectory, the summary and trials like a scene's guarantee. A raising ``func``
        (``SimulationError``, the cause chained) or a non-finite margin (``NumericError``) stops
        the run with an exception naming the guarantee. Call before the first step."""
    def step(self, n: int = 1) -> None: ...
    def run_until(self, t_s: float) -> None: ...
    def monitor(self) -> Dict[str, Any]: ...
    def docking(self) -> Optional[Dict[str, Any]]:
        """Names, ``seat_depth_m``, ``mouth_radius_m``, ``state``, ``reason``, ``t_latch_s``,
        ``spec`` (the scene's ``docking`` entry: ``magnet``, ``latch``, ``miss``, ``contact``)
        and ``contact_model``."""
    def release_docking(self) -> None:
        """Commands the docking mechanism to release at the next step (``RELEASED`` and the
        separation springs when latched, else a ``docking_release_ignored`` event); ValueError
        without a docking mechanism."""
    def render(
        self,
        width: int = 480,
        height: int = 360,
        look_dir: Optional[_Vec] = None,
        up: Optional[_Vec] = None,
        centre_m: Optional[_Vec] = None,
        span_m: Optional[float] = None,
        fit_only: bool = False,
    ) -> Any:
        """A ``(height, width, 3)`` ``uint8`` orthographic picture of every collider (or, with
        ``fit_only``, the fitted view ``{"centre_m", "span_m"}``)."""
    def events(self) -> List[Dict[str, Any]]: ...
    def summary(self) -> Dict[str, Any]: ...
    def finish(self, out_dir: Optional[_Path] = None) -> Dict[str, Any]: ...
