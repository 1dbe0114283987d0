"""The gear pump model from Python.

``simulate`` runs one operating point and returns the dict of
``gearpump simulate --json``; ``simulate_batch`` runs many points (rows of
arrays or a pandas DataFrame) in parallel in Rust with the GIL released;
``montecarlo`` runs a tolerance study (``gearpump montecarlo``) in this
process or on Dask distributed.
Bad input raises ``ValueError`` with the CLI's message; a failed simulation
raises ``RuntimeError`` (``simulate``) or gives a NaN row (``simulate_batch``).
"""

from __future__ import annotations

from typing import Any, Callable, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _gearpump
from ._gearpump import campaign, diagnose, simulate

__all__ = ["simulate", "simulate_batch", "montecarlo", "campaign", "diagnose", "COLUMNS",
           "RESULTS"]

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


def montecarlo(
    pumps: int = 200,
    seed: int = 1,
    *,
    design: Optional[str] = None,
    set: Optional[Sequence[str]] = None,
    fit: Optional[str] = None,
    distributions: Optional[str] = None,
    conditions: Union[str, Sequence[Tuple[float, float, float]]] = "paper",
    spec: Optional[Sequence[str]] = None,
    sensitivity: bool = True,
    micromotion: bool = True,
    out: Optional[str] = None,
    chunk: Optional[int] = None,
    jobs: Optional[int] = None,
    scheduler: Any = None,
    workers: int = 2,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Dict[str, Any]:
    """A Monte Carlo tolerance study, as ``gearpump montecarlo``.

    ``pumps`` pumps are drawn from the clearance population (the paper's
    statistics; ``fit``: normal distributions fitted to a measured campaign
    CSV; ``distributions``: a TOML file of the user's), pump ``i`` from its
    own random stream of ``seed``, and simulated at every condition
    (``"paper"``, a CSV path, or a list of ``(pressure_bar, speed_rpm,
    temp_c)``) with the design (``design``, ``set`` as the CLI's). With
    ``sensitivity`` the pick-freeze runs of the Sobol indices are added
    (twice as many runs again). ``spec``: strings such as
    ``"eta_v>=0.85@500rpm,30bar,120degC"`` (docs/interfaces.md).

    Where it runs:

    * ``scheduler=None``, ``out=None``: in this process, in Rust on
      ``jobs`` threads (all cores when None), nothing written.
    * ``scheduler=None``, ``out=DIR``: the command line's study: journaled
      in ``DIR`` (an interrupted study resumes), its files written there.
    * ``scheduler="local"`` (a ``LocalCluster`` of ``workers`` processes),
      a scheduler address, or a ``distributed.Client``: on Dask, in chunks
      of ``chunk`` items (default 16) per task, streamed to Parquet files in
      ``out`` (required; a rerun resumes from them); see
      ``gearpump.distributed``.

    Returns a dict: ``record`` (the content of montecarlo.json: the study
    and its ``summary`` with per-condition distributions, yields and
    indices) and ``runs`` (numpy arrays ``eta_v``, ``flow_lpm``,
    ``torque_nm`` of every run, row ``item * n_conditions + condition``,
    NaN where a simulation failed, and ``errors``: (row, message) pairs);
    the same study gives the same numbers, to the bit, on every path.
    Raises ValueError on bad input, with the CLI's message.
    """
    study: Dict[str, Any] = {
        "design": None if design is None else str(design),
        "set": None if set is None else [str(x) for x in set],
        "pumps": pumps,
        "seed": seed,
        "fit": None if fit is None else str(fit),
        "distributions": None if distributions is None else str(distributions),
        "conditions": conditions if isinstance(conditions, str)
        else [tuple(float(x) for x in c) for c in conditions],
        "spec": None if spec is None else [str(x) for x in spec],
        "sensitivity": bool(sensitivity),
        "micromotion": bool(micromotion),
    }
    if scheduler is not None:
        if out is None:
            raise ValueError("out: a study on Dask streams its chunks to a folder: give out=DIR")
        from . import distributed

        return distributed.run(study, scheduler=scheduler, workers=workers, out=out,
                               chunk=16 if chunk is None else chunk, progress=progress)
    if out is not None:
        r = _gearpump.montecarlo_run(study, str(out), chunk=8 if chunk is None else chunk,
                                     jobs=jobs)
        return r
    plan = _gearpump.montecarlo_plan(study, 1)
    runs = _gearpump.montecarlo_chunk(study, 0, plan["items"], jobs=jobs)
    record = _gearpump.montecarlo_summarize(study, runs["eta_v"], runs["flow_lpm"],
                                            runs["torque_nm"])
    return {"record": record, "runs": runs}
