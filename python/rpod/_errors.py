"""rpod's exceptions, defined in Python (the extension raises them) so that they pickle by name
(``rpod.SceneError``, …) with their attributes: an error in a worker process reaches its parent
(multiprocessing, Gymnasium's ``AsyncVectorEnv``).

An exception made from another of its kind takes over its attributes: Gymnasium's
``AsyncVectorEnv`` re-raises a worker's error ``e`` as ``type(e)(e)``, and ``.field``, ``.line``
and the rest survive that too.
"""

from __future__ import annotations


class _RpodError(Exception):
    def __init__(self, *args):
        super().__init__(*args)
        if len(args) == 1 and isinstance(args[0], type(self)):
            self.__dict__.update(args[0].__dict__)


class SceneError(_RpodError):
    """A scene that cannot be loaded: ``.file``, ``.line``, ``.column`` (1-based, 0 when
    unknown), ``.field`` (e.g. ``bodies.chaser.mass_kg``) and ``.message``; ``str(e)`` is the
    CLI's message."""


class NumericError(_RpodError):
    """A non-finite or overflowing number (a command, a state): the message names the body, the
    quantity and the simulated time."""


class SimulationError(_RpodError):
    """The simulation cannot go on (a failure inside rpod, a finished or stopped run, a use
    from another thread); the message says why."""


for _c in (SceneError, NumericError, SimulationError):
    _c.__module__ = "rpod"
del _c
