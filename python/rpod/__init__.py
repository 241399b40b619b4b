"""rpod in Python: spacecraft rendezvous, proximity operations and docking on a real physics
engine (Bevy + rapier), with Python control laws hosted inside rpod's fixed-step pipeline,
the interval-sound full-geometry monitor, the docking mechanism and the standard outputs.

>>> import rpod
>>> sim = rpod.Simulation("scenes/orbit_approach_latch.ron", record=False)
>>> sim.run_until(10.0)
>>> sim.state("chaser")["pos_m"]          # world frame, m
>>> sim.monitor()["guarantees"][0]["margin"]

Units are in every name (``_m``, ``_m_s``, ``_rad_s``, ``_n``, ``_nm``, ``_s``); frames are named
(``world``, ``body``, ``hill``, ``target_body``, port frames). See ``rpod.gym`` for the
Gymnasium environment (``pip install ./python[gym]``).
"""

from ._rpod import NumericError, SceneError, Simulation, SimulationError, __version__

__all__ = ["Simulation", "SceneError", "NumericError", "SimulationError", "__version__"]
