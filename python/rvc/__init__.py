"""rvc's monitors in Python: past-time temporal logic (Reelay's Rye syntax) checked in-process.

Two APIs over one engine (docs/python.md):

* Reelay's, unchanged: ``discrete_timed_monitor(pattern=..., condense=...)``,
  ``dense_timed_monitor(...)``, ``m.update(dict)`` returning what Reelay returns.
* rvc's own: ``Monitor`` (several properties at once, explanations, typed ROS 2
  messages from CDR bytes, batches from lists and numpy structured arrays) and
  ``check_bag`` (a ROS 2 bag's topic), returning ``Verdict`` objects and, where
  pandas is installed, DataFrames.
"""
from __future__ import annotations

from ._rvc import DenseTimedMonitor, DiscreteTimedMonitor, has_mcap
from .monitor import BagResult, Monitor, Verdict, check_bag, to_dataframe

__all__ = ["discrete_timed_monitor", "dense_timed_monitor", "Monitor", "Verdict", "BagResult", "check_bag", "to_dataframe", "has_mcap"]
__version__ = "0.1.0"


def _semantics(semantics: str) -> bool:
    if semantics not in ("boolean", "robustness"):
        raise AttributeError("semantics must be either 'boolean' or 'robustness'.")
    return semantics == "robustness"


def discrete_timed_monitor(pattern: str, semantics: str = "boolean", t_name: str = "time", y_name: str = "value",
                           condense: bool = True) -> DiscreteTimedMonitor:
    """Reelay's discrete_timed_monitor: update(dict) returns {t_name: step, y_name: value} when the
    value changed (condense=True; always on the first call), else {}; with condense=False
    {y_name: value} at every step. semantics='robustness' gives float margins."""
    return DiscreteTimedMonitor(pattern, _semantics(semantics), t_name, y_name, condense)


def dense_timed_monitor(pattern: str, semantics: str = "boolean", piecewise: str = "constant", t_name: str = "time",
                        y_name: str = "value") -> DenseTimedMonitor:
    """Reelay's dense_timed_monitor: update(dict) (with a "time" key) returns the list of changes
    [{t_name: time, y_name: value}, ...] since the previous message. Piecewise-constant signals
    only: rvc does not interpolate (piecewise='linear' is refused)."""
    robust = _semantics(semantics)
    if piecewise == "linear":
        raise AttributeError("rvc evaluates piecewise-constant signals only: piecewise='linear' is not available "
                             "(docs/python.md, differences from Reelay)")
    if piecewise != "constant":
        raise AttributeError("piecewise must be either 'constant' or 'linear'.")
    return DenseTimedMonitor(pattern, robust, t_name, y_name)
