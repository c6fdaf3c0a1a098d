"""Fig. sim4: goals never seen in training, through the context map h (Secs. IV-C, V-D), notebook 07.

The grasp error at a new cup is fitted against the cup's distance (both over the farthest cup's) through
the origin, uncentred R^2, as the paper does; readings ``@joint_space``, ``@intercept``, ``@ee_line``.
:mod:`.episodes` runs the users, :mod:`.analysis` fits and judges, :mod:`.figure` draws.
"""

from lasa.experiments.sim4.analysis import boot_values, claims
from lasa.experiments.sim4.episodes import COLUMNS, NAME, Config, run
from lasa.experiments.sim4.figure import plot

__all__ = ["NAME", "COLUMNS", "Config", "run", "claims", "boot_values", "plot"]
