"""rpod in Python: spacecraft rendezvous, proximity operations and docking on a real physics
engine (Bevy + rapier), with Python control laws hosted inside rpod's fixed-step pipeline,
the interval-sound full-geometry monitor, the docking mechanism and the standard outputs.

>>> import rpod
>>> sim = rpod.Simulation(rpod.scenes.path("orbit_approach_latch"), record=False)
>>> sim.run_until(10.0)
>>> sim.state("chaser")["pos_m"]          # world frame, m
>>> sim.monitor()["guarantees"][0]["margin"]

Units are in every name (``_m``, ``_m_s``, ``_rad_s``, ``_n``, ``_nm``, ``_s``); frames are named
(``world``, ``body``, ``hill``, ``target_body``, port frames). ``rpod.scenes`` holds the
repository's scenes; ``rpod.gym`` the Gymnasium environment (``pip install 'rpod[gym]'``).
A ``Simulation`` belongs to the thread that created it (any other raises ``SimulationError``).
The exceptions pickle (they are defined here, in ``rpod``), so a worker process's error reaches
its parent (multiprocessing, Gymnasium's ``AsyncVectorEnv``).
"""

from . import scenes
from ._rpod import NumericError, SceneError, Simulation, SimulationError, __version__

__all__ = ["Simulation", "SceneError", "NumericError", "SimulationError", "scenes", "__version__"]
