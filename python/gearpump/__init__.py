"""The gear pump model from Python.

``simulate`` runs one operating point and returns the dict of
``gearpump simulate --json``; ``simulate_batch`` runs many points (rows of
arrays or a pandas DataFrame) in parallel in Rust with the GIL released;
``montecarlo`` runs a tolerance study (``gearpump montecarlo``) in this
process or on Dask distributed.
Bad input raises ``ValueError`` (a wrong value) or ``TypeError`` (a wrong
type: a string, bool, complex, datetime ... where a number is expected)
whose message starts with the argument's name (``row i, column c:`` for a
batch row), followed by the CLI's text where the CLI has one; a failed
simulation raises ``RuntimeError`` (``simulate``) or gives a NaN row
(``simulate_batch``). A ``jobs`` above the cores available is clamped to
them with a ``UserWarning`` (the CLI's note).
"""

from __future__ import annotations

import numbers
import os
from typing import (Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple,
                    Union)

import numpy as np

from . import _gearpump

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


# ---------------------------------------------------------------- checks
# The Python types of the arguments, checked here so that a wrong type is a
# TypeError naming the argument (not the conversion's bare message, nor a
# value silently converted: a bool is not a speed, a string is not a list
# of its characters). The values are checked in Rust, with the CLI's text.

def _type_name(v: Any) -> str:
    return type(v).__name__


def _is_real(v: Any) -> bool:
    """An int or float, Python or numpy; not a bool, complex, datetime,
    timedelta (a numpy int subclass) nor a string."""
    if isinstance(v, (bool, np.bool_, np.datetime64, np.timedelta64)):
        return False
    return isinstance(v, numbers.Real)


def _real(name: str, v: Any) -> float:
    if isinstance(v, np.ndarray) and v.ndim == 0 and v.dtype.kind in "iuf":
        v = v[()]
    if not _is_real(v):
        raise TypeError(f"{name}: must be a real number, not {_type_name(v)}")
    try:
        return float(v)
    except OverflowError:
        raise ValueError(f"{name}: {v} is too large for a float") from None


def _flag(name: str, v: Any) -> bool:
    if not isinstance(v, (bool, np.bool_)):
        raise TypeError(f"{name}: must be True or False, not {_type_name(v)}")
    return bool(v)


def _path(name: str, v: Any, optional: bool = True) -> Optional[str]:
    if v is None and optional:
        return None
    p = os.fspath(v) if isinstance(v, (str, os.PathLike)) else None
    if not isinstance(p, str):
        raise TypeError(f"{name}: expected a path (str or os.PathLike), not {_type_name(v)}")
    return p


def _strings(name: str, v: Any) -> Optional[List[str]]:
    """None, a string (one item: not split into its characters) or an
    iterable of strings."""
    if v is None:
        return None
    if isinstance(v, str):
        return [v]
    if isinstance(v, (bytes, bytearray, Mapping)) or not hasattr(v, "__iter__"):
        raise TypeError(f"{name}: expected a string or a list of strings, not {_type_name(v)}")
    out = list(v)
    for i, x in enumerate(out):
        if not isinstance(x, str):
            raise TypeError(f"{name}[{i}]: must be a string, not {_type_name(x)}")
    return out


def _sequence(name: str, v: Any) -> List[Any]:
    if isinstance(v, np.ndarray):
        if v.ndim != 1:
            raise ValueError(f"{name}: expected a 1-D sequence, got a {v.ndim}-D array")
        return list(v)
    if isinstance(v, (str, bytes, bytearray, Mapping)) or not hasattr(v, "__iter__"):
        raise TypeError(f"{name}: expected a sequence of numbers, not {_type_name(v)}")
    return list(v)


def _column(name: str, v: Any) -> np.ndarray:
    """A batch column as 1-D float64: ints and floats only (a bool,
    datetime, timedelta, complex, string or object column is refused, not
    converted)."""
    where = f"conditions: column {name!r}"
    kind = getattr(getattr(v, "dtype", None), "kind", None)
    if kind is None:
        if isinstance(v, (str, bytes)) or not hasattr(v, "__iter__"):
            raise TypeError(f"{where}: expected a 1-D array or list of numbers, "
                            f"not {_type_name(v)}")
        items = list(v)
        for i, x in enumerate(items):
            if not _is_real(x):
                raise TypeError(f"row {i}, column {name}: must be a real number, "
                                f"not {_type_name(x)}")
        a = np.asarray(items, dtype=np.float64) if items else np.zeros(0)
    else:
        if kind not in "iuf":
            what = {"b": "bool", "M": "datetime64", "m": "timedelta64", "c": "complex",
                    "U": "str", "S": "bytes", "O": "object"}.get(kind, str(v.dtype))
            raise TypeError(f"{where}: must hold real numbers (int or float), "
                            f"not {what} (dtype {v.dtype})")
        if hasattr(v, "to_numpy"):  # a pandas Series, nullable Int64/Float64 too
            a = v.to_numpy(dtype=np.float64, na_value=np.nan)
        else:
            a = np.asarray(v, dtype=np.float64)
    a = np.ascontiguousarray(a)
    if a.ndim != 1:
        raise ValueError(f"{where} must be 1-D, got {a.ndim}-D")
    return a


def _conditions(v: Any) -> Union[str, List[Tuple[float, ...]]]:
    if isinstance(v, (str, os.PathLike)):
        return _path("conditions", v)  # type: ignore[return-value]
    what = "expected \"paper\", a CSV path or a list of (pressure_bar, speed_rpm, temp_c)"
    if isinstance(v, (bytes, bytearray, Mapping)) or not hasattr(v, "__iter__"):
        raise TypeError(f"conditions: {what}, not {_type_name(v)}")
    rows = []
    for i, c in enumerate(v):
        if isinstance(c, (str, bytes)) or not hasattr(c, "__iter__"):
            raise TypeError(f"conditions[{i}]: {what}; this row is {_type_name(c)}")
        rows.append(tuple(_real(f"conditions[{i}][{j}]", x) for j, x in enumerate(c)))
    return rows


def simulate(
    speed_rpm: float,
    pressure_bar: float,
    temp_c: float,
    *,
    design: Optional[Union[str, "os.PathLike[str]"]] = None,
    set: Optional[Union[str, Sequence[str]]] = None,
    inlet_pressure_bar: float = 1.01325,
    sample_clearances_um: Optional[Sequence[float]] = None,
    micromotion: bool = True,
) -> Dict[str, Any]:
    """Simulates one operating point to its periodic state.

    ``speed_rpm`` (rpm), ``pressure_bar`` (delivery, bar above the inlet),
    ``temp_c`` (oil, degC); ``design`` a design TOML (the bundled seed pump
    when None), ``set`` overrides as "key.path=value" strings (one string
    is one override), ``inlet_pressure_bar`` absolute,
    ``sample_clearances_um`` a sample's four clearances [tip1, tip2,
    bearing1, bearing2] in um.

    Returns the object of ``gearpump simulate --json`` (same keys, same
    units: flow_lpm, eta_v, torque_nm, eta_hm, losses, warnings, ...).
    Raises ValueError on bad input (the CLI's message, after the argument's
    name), TypeError on a wrong type (a number that is a string, bool,
    complex ...: the message names the argument) and RuntimeError when the
    simulation fails. The GIL is released while the pump is built and
    simulated.
    """
    clearances = None
    if sample_clearances_um is not None:
        clearances = [_real(f"sample_clearances_um[{i}]", x)
                      for i, x in enumerate(_sequence("sample_clearances_um",
                                                      sample_clearances_um))]
    return _gearpump.simulate(
        _real("speed_rpm", speed_rpm), _real("pressure_bar", pressure_bar),
        _real("temp_c", temp_c), design=_path("design", design), set=_strings("set", set),
        inlet_pressure_bar=_real("inlet_pressure_bar", inlet_pressure_bar),
        sample_clearances_um=clearances, micromotion=_flag("micromotion", micromotion),
    )


def campaign(
    data: Union[str, "os.PathLike[str]"],
    out: Union[str, "os.PathLike[str]"],
    *,
    design: Optional[Union[str, "os.PathLike[str]"]] = None,
    set: Optional[Union[str, Sequence[str]]] = None,
    jobs: Optional[int] = None,
    micromotion: bool = True,
) -> Dict[str, Any]:
    """``gearpump campaign``: every test of the measured campaign ``data``
    simulated with its pump's clearances, the outputs written (and the
    journal kept while running) in ``out``; returns the object of its
    ``--json`` (rows that failed are listed in ``failed``). ValueError on
    bad input (the CLI's message; an ``out`` that cannot be made or written
    names ``out``), TypeError on a wrong type, RuntimeError otherwise."""
    return _gearpump.campaign(
        _path("data", data, optional=False), _path("out", out, optional=False),
        design=_path("design", design), set=_strings("set", set), jobs=jobs,
        micromotion=_flag("micromotion", micromotion),
    )


def diagnose(
    data: Union[str, "os.PathLike[str]"],
    out: Union[str, "os.PathLike[str]"],
    *,
    design: Optional[Union[str, "os.PathLike[str]"]] = None,
    set: Optional[Union[str, Sequence[str]]] = None,
    jobs: Optional[int] = None,
    micromotion: bool = True,
) -> Dict[str, Any]:
    """``gearpump diagnose``: returns the object of diagnosis.json (causes,
    gain, extended design, ...), its files written in ``out``. Errors as
    ``campaign``."""
    return _gearpump.diagnose(
        _path("data", data, optional=False), _path("out", out, optional=False),
        design=_path("design", design), set=_strings("set", set), jobs=jobs,
        micromotion=_flag("micromotion", micromotion),
    )


def simulate_batch(
    conditions: Union[Mapping[str, Union[Sequence[float], np.ndarray]], Any],
    *,
    design: Optional[Union[str, "os.PathLike[str]"]] = None,
    set: Optional[Union[str, Sequence[str]]] = None,
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
    and carries the CLI's text; ``jobs`` < 1) and TypeError on a wrong
    type (a bool, datetime, timedelta, complex, string or object column:
    only ints and floats are numbers here). ``jobs`` above the cores
    available is clamped to them with a UserWarning.
    """
    frame = _is_dataframe(conditions)
    if not frame and not isinstance(conditions, Mapping):
        raise TypeError("conditions: expected a mapping of arrays or a pandas DataFrame")
    cols: Dict[str, np.ndarray] = {}
    for key in conditions.keys():
        name = str(key)
        cols[name] = _column(name, conditions[key])
    out = _gearpump.simulate_batch(
        cols, design=_path("design", design), set=_strings("set", set),
        micromotion=_flag("micromotion", micromotion), jobs=jobs,
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
    design: Optional[Union[str, "os.PathLike[str]"]] = None,
    set: Optional[Union[str, Sequence[str]]] = None,
    fit: Optional[Union[str, "os.PathLike[str]"]] = None,
    distributions: Optional[Union[str, "os.PathLike[str]"]] = None,
    conditions: Union[str, "os.PathLike[str]", Sequence[Tuple[float, float, float]]] = "paper",
    spec: Optional[Union[str, Sequence[str]]] = None,
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
    Raises ValueError on bad input, with the CLI's message after the
    argument's name (``pumps``, ``seed``, ``jobs``, ``chunk`` out of their
    range included), TypeError on a wrong type (naming the argument). A
    single string for ``set`` or ``spec`` is one item. ``jobs`` above the
    cores available is clamped to them with a UserWarning.
    """
    study: Dict[str, Any] = {
        "design": _path("design", design),
        "set": _strings("set", set),
        "pumps": pumps,
        "seed": seed,
        "fit": _path("fit", fit),
        "distributions": _path("distributions", distributions),
        "conditions": _conditions(conditions),
        "spec": _strings("spec", spec),
        "sensitivity": _flag("sensitivity", sensitivity),
        "micromotion": _flag("micromotion", micromotion),
    }
    out = _path("out", out)
    if scheduler is not None:
        if out is None:
            raise ValueError("out: a study on Dask streams its chunks to a folder: give out=DIR")
        from . import distributed

        return distributed.run(study, scheduler=scheduler, workers=workers, out=out,
                               chunk=16 if chunk is None else chunk, progress=progress)
    if out is not None:
        return _gearpump.montecarlo_run(study, out, chunk=chunk, jobs=jobs)
    plan = _gearpump.montecarlo_plan(study, 1)
    runs = _gearpump.montecarlo_chunk(study, 0, plan["items"], jobs=jobs)
    record = _gearpump.montecarlo_summarize(study, runs["eta_v"], runs["flow_lpm"],
                                            runs["torque_nm"])
    return {"record": record, "runs": runs}
