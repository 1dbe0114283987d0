"""The gear pump model from Python.

``simulate`` runs one operating point and returns the dict of
``gearpump simulate --json``; ``simulate_batch`` runs many points (rows of
arrays or a pandas DataFrame) in parallel in Rust with the GIL released.
Bad input raises ``ValueError`` with the CLI's message; a failed simulation
raises ``RuntimeError`` (``simulate``) or gives a NaN row (``simulate_batch``).
"""

from __future__ import annotations

from typing import Any, Dict, Mapping, Optional, Sequence, Union

import numpy as np

from . import _gearpump
from ._gearpump import simulate

__all__ = ["simulate", "simulate_batch", "COLUMNS", "RESULTS"]

#: The columns ``simulate_batch`` reads (the first three are required).
COLUMNS = (
    "speed_rpm",
    "pressure_bar",
    "temp_c",
    "tip1_um",
    "tip2_um",
    "bearing1_um",
    "bearing2_um",
    "inlet_pressure_bar",
)

#: The result columns of ``simulate_batch`` (besides ``errors``).
RESULTS = ("eta_v", "flow_lpm", "torque_nm", "eta_hm", "flow_ripple_lpm", "converged")


def _is_dataframe(x: Any) -> bool:
    # without importing pandas: it is only needed when a DataFrame is passed
    t = type(x)
    return t.__name__ == "DataFrame" and t.__module__.split(".")[0] == "pandas"


def simulate_batch(
    conditions: Union[Mapping[str, Union[Sequence[float], np.ndarray]], Any],
    *,
    design: Optional[str] = None,
    set: Optional[Sequence[str]] = None,
    micromotion: bool = True,
    jobs: Optional[int] = None,
) -> Union[Dict[str, Any], Any]:
    """Simulates many operating points (rows) of one design in parallel.

    ``conditions`` is a mapping of equal-length 1-D arrays (or lists), or a
    pandas DataFrame, with the columns ``speed_rpm``, ``pressure_bar``
    (gauge), ``temp_c`` and optionally ``tip1_um``, ``tip2_um``,
    ``bearing1_um``, ``bearing2_um`` (a sample's clearances; the design's
    nominal ones when absent) and ``inlet_pressure_bar`` (absolute, default
    1.01325). The pump is built once; the rows run in parallel on ``jobs``
    threads (all cores when None) with the GIL released.

    Returns a dict of numpy arrays ``eta_v``, ``flow_lpm``, ``torque_nm``,
    ``eta_hm``, ``flow_ripple_lpm`` (float64) and ``converged`` (bool), plus
    ``errors`` (a list: None, or the message of a row whose simulation
    failed; such a row is NaN and not converged). Given a DataFrame, returns
    a DataFrame with those columns (``errors`` as ``error``) on its index.

    Raises ValueError on bad input (unknown or missing column, unequal
    lengths, a value out of range: the message names the row and column
    and carries the CLI's text).
    """
    frame = _is_dataframe(conditions)
    if not frame and not isinstance(conditions, Mapping):
        raise TypeError("conditions: expected a mapping of arrays or a pandas DataFrame")
    cols: Dict[str, np.ndarray] = {}
    for key in conditions.keys():
        name = str(key)
        try:
            a = np.ascontiguousarray(np.asarray(conditions[key], dtype=np.float64))
        except (TypeError, ValueError) as e:
            raise ValueError(f"conditions: column {name!r} is not numeric: {e}") from None
        if a.ndim != 1:
            raise ValueError(f"conditions: column {name!r} must be 1-D, got {a.ndim}-D")
        cols[name] = a
    out = _gearpump.simulate_batch(
        cols, design=None if design is None else str(design),
        set=None if set is None else list(set), micromotion=micromotion, jobs=jobs,
    )
    if not frame:
        return out
    import pandas as pd

    data = {k: out[k] for k in RESULTS}
    data["error"] = out["errors"]
    return pd.DataFrame(data, index=conditions.index)
