"""Type hints of the Rust extension gearpump._gearpump (PyO3)."""

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
    name) and RuntimeError when the simulation fails. The GIL is released
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
