"""Type hints of the Rust extension gearpump._gearpump (PyO3).

The package's public functions (gearpump.simulate, simulate_batch,
montecarlo, campaign, diagnose) are Python wrappers that check the
arguments' Python types first (TypeError naming the argument; a single
string for ``set``/``spec`` is one item) and call these. Here: ``jobs``,
``chunk``, ``start``, ``end`` are ints (a bool or another type: TypeError
naming it; below their least value, negative included: ValueError
``"jobs: must be >= 1, got -1"``); a ``jobs`` above the cores available
is clamped to them with a UserWarning; an output folder ``out`` that
cannot be made or written is a ValueError naming ``out``.
"""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np

def simulate(
    speed_rpm: float,
    pressure_bar: float,
    temp_c: float,
    *,
    design: Optional[Union[str, PathLike[str]]] = None,
    set: Optional[Sequence[str]] = None,
    inlet_pressure_bar: float = 1.01325,
    sample_clearances_um: Optional[Sequence[float]] = None,
    micromotion: bool = True,
) -> Dict[str, Any]:
    """Simulates one operating point to its periodic state.

    ``speed_rpm`` (rpm), ``pressure_bar`` (delivery, bar above the inlet),
    ``temp_c`` (oil, degC); ``design`` a design TOML (the bundled seed pump
    when None), ``set`` overrides as "key.path=value" strings,
    ``inlet_pressure_bar`` absolute, ``sample_clearances_um`` a sample's
    four clearances [tip1, tip2, bearing1, bearing2] in um.

    Returns the object of ``gearpump simulate --json`` (same keys, same
    units: flow_lpm, eta_v, torque_nm, eta_hm, losses, warnings, ...).
    Raises ValueError on bad input (the CLI's message, after the argument's
    name) and RuntimeError when the simulation fails (gearpump.simulate adds
    the TypeError of a wrong-typed argument). The GIL is released
    while the pump is built and simulated.
    """

def simulate_batch(
    conditions: Dict[str, np.ndarray],
    *,
    design: Optional[Union[str, PathLike[str]]] = None,
    set: Optional[Sequence[str]] = None,
    micromotion: bool = True,
    jobs: Optional[int] = None,
) -> Dict[str, Union[np.ndarray, List[Optional[str]]]]:
    """The rows of ``conditions`` (a dict of 1-D float64 arrays) in parallel;
    see ``gearpump.simulate_batch`` (which also takes lists and DataFrames)."""

# The Monte Carlo study (see gearpump.montecarlo): `study` is the dict it
# builds (keys design, set, pumps, seed, fit, distributions, conditions,
# spec, sensitivity, micromotion).

def montecarlo_plan(study: Dict[str, Any], chunk: int) -> Dict[str, Any]:
    """The study's items, rows, conditions, chunks of ``chunk`` items and
    fingerprint (for resuming)."""

def montecarlo_chunk(
    study: Dict[str, Any], start: int, end: int, jobs: Optional[int] = None
) -> Dict[str, Any]:
    """The runs of items ``start..end`` at every condition (arrays eta_v,
    flow_lpm, torque_nm; errors as (row, message)), GIL released."""

def montecarlo_summarize(
    study: Dict[str, Any], eta_v: np.ndarray, flow_lpm: np.ndarray, torque_nm: np.ndarray
) -> Dict[str, Any]:
    """The record of montecarlo.json from every row's results (1-D float64
    arrays; integer arrays are converted, another dtype is a TypeError
    naming the argument)."""

def montecarlo_run(
    study: Dict[str, Any], out: str, chunk: Optional[int] = None, jobs: Optional[int] = None
) -> Dict[str, Any]:
    """The command line's study: journaled and written in ``out`` (``chunk``
    items per journal entry, 8 when None)."""

def campaign(
    data: Union[str, PathLike[str]],
    out: Union[str, PathLike[str]],
    *,
    design: Optional[Union[str, PathLike[str]]] = None,
    set: Optional[Sequence[str]] = None,
    jobs: Optional[int] = None,
    micromotion: bool = True,
) -> Dict[str, Any]:
    """``gearpump campaign``: every test of the measured campaign ``data``
    simulated with its pump's clearances, the outputs written (and the
    journal kept while running) in ``out``; returns the object of its
    ``--json`` (rows that failed are listed in ``failed``). ValueError on
    bad input (the CLI's message), RuntimeError otherwise."""

def diagnose(
    data: Union[str, PathLike[str]],
    out: Union[str, PathLike[str]],
    *,
    design: Optional[Union[str, PathLike[str]]] = None,
    set: Optional[Sequence[str]] = None,
    jobs: Optional[int] = None,
    micromotion: bool = True,
) -> Dict[str, Any]:
    """``gearpump diagnose``: returns the object of diagnosis.json (causes,
    gain, extended design, ...), its files written in ``out``."""
