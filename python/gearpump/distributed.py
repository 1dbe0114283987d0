"""A Monte Carlo study on Dask distributed (``gearpump.montecarlo(...,
scheduler=...)`` calls this).

The study's items (pumps and the sensitivity runs' hybrids, see
``gearpump.montecarlo``) are cut into chunks of ``chunk`` items; each chunk
is one Dask task that runs all its simulations (every condition) in Rust on
the worker (``_gearpump.montecarlo_chunk``, GIL released, ``jobs_per_task``
threads) and returns its columns. Pump ``i`` is drawn from its own random
stream of the seed, so a chunk gives the same numbers on any worker.

As each task finishes, the client writes its rows to
``OUT/chunk-NNNNNN.parquet`` (columns ``row``, ``eta_v``, ``flow_lpm``,
``torque_nm``, ``error``; written to a temporary name and renamed, so a
file is whole or absent). ``OUT/study.json`` holds the study and its
fingerprint (the study, the design text, the chunk size and the
extension's build); a rerun of the same study skips the chunks already
written, a different study in the same folder discards them first. When
every chunk is in, the columns are read back in row order and summarised
by the same Rust function as the single-process study, so the two agree
to the bit.

``scheduler``: ``"local"`` starts a ``LocalCluster`` of ``workers``
processes with one thread each on this machine (closed at the end); a
string such as ``"tcp://10.0.0.5:8786"`` connects to that scheduler (its
workers need this package installed); a ``distributed.Client`` is used as
it is.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Tuple

import numpy as np

from . import _gearpump

#: The columns of a chunk file.
CHUNK_COLUMNS = ("row", "eta_v", "flow_lpm", "torque_nm", "error")


def _run_chunk(study: Dict[str, Any], c: int, start: int, end: int,
               jobs: Optional[int]) -> Tuple[int, Dict[str, Any]]:
    """The task: chunk ``c`` (items ``start..end``) on a worker."""
    from gearpump import _gearpump as ext

    return c, ext.montecarlo_chunk(study, start, end, jobs=jobs)


def _build_identity() -> str:
    """The extension's file size and modification time: a rebuilt extension
    invalidates chunks written by the old one."""
    st = os.stat(_gearpump.__file__)
    return f"{st.st_size}-{st.st_mtime_ns}"


def _chunk_path(out: Path, c: int) -> Path:
    return out / f"chunk-{c:06d}.parquet"


def _write_chunk(out: Path, c: int, start_row: int, d: Dict[str, Any]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    n = len(d["eta_v"])
    rows = np.arange(start_row, start_row + n, dtype=np.int64)
    errors = [None] * n
    for r, msg in d["errors"]:
        errors[r - start_row] = msg
    table = pa.table({
        "row": rows,
        "eta_v": np.asarray(d["eta_v"], dtype=np.float64),
        "flow_lpm": np.asarray(d["flow_lpm"], dtype=np.float64),
        "torque_nm": np.asarray(d["torque_nm"], dtype=np.float64),
        "error": pa.array(errors, type=pa.string()),
    })
    final = _chunk_path(out, c)
    tmp = final.with_name(f".{final.name}.tmp-{os.getpid()}")
    pq.write_table(table, tmp)
    with open(tmp, "rb") as f:
        os.fsync(f.fileno())
    os.replace(tmp, final)


def _read_chunks(out: Path, nchunks: int, rows: int) -> Dict[str, Any]:
    import pyarrow.parquet as pq

    cols = {k: np.empty(rows, dtype=np.float64) for k in ("eta_v", "flow_lpm", "torque_nm")}
    errors = []
    seen = 0
    for c in range(nchunks):
        t = pq.read_table(_chunk_path(out, c))
        r = t.column("row").to_numpy()
        for k in cols:
            cols[k][r] = t.column(k).to_numpy()
        for row, msg in zip(r.tolist(), t.column("error").to_pylist()):
            if msg is not None:
                errors.append((row, msg))
        seen += len(r)
    if seen != rows:
        raise RuntimeError(f"{out}: the chunk files hold {seen} rows, the study has {rows}")
    return {**cols, "errors": errors}


def run(study: Dict[str, Any], *, scheduler: Any = "local", workers: int = 2,
        out: Any, chunk: int = 16, jobs_per_task: Optional[int] = 1,
        progress: Optional[Callable[[int, int], None]] = None) -> Dict[str, Any]:
    """Runs ``study`` (the dict ``gearpump.montecarlo`` builds) on Dask,
    streaming chunks to ``out`` (module doc). Returns the record (the
    content of montecarlo.json), the runs' columns, and how many chunks
    were computed and reused."""
    from distributed import Client, LocalCluster, as_completed

    if isinstance(workers, bool) or not isinstance(workers, int):
        raise TypeError(f"workers: must be an integer, not {type(workers).__name__}")
    if workers < 1:
        raise ValueError(f"workers: must be an integer >= 1, got {workers!r}")
    plan = _gearpump.montecarlo_plan(study, chunk)
    fingerprint = f"{plan['fingerprint']}-{_build_identity()}"
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out: {out} exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"out: {out}: cannot make the folder ({e.strerror or e})") from None
    manifest = out / "study.json"
    old = None
    if manifest.exists():
        try:
            old = json.loads(manifest.read_text()).get("fingerprint")
        except (ValueError, OSError):
            old = None
    if old != fingerprint:
        for f in out.glob("chunk-*.parquet"):
            f.unlink()
        tmp = out / ".study.json.tmp"
        tmp.write_text(json.dumps({"fingerprint": fingerprint, "chunk": chunk,
                                   "study": study}, indent=1, default=str) + "\n")
        os.replace(tmp, manifest)
    for f in out.glob(".chunk-*.tmp-*"):
        f.unlink()
    nchunks = plan["chunks"]
    nc = len(plan["conditions"])
    items = plan["items"]
    todo = [c for c in range(nchunks) if not _chunk_path(out, c).exists()]
    reused = nchunks - len(todo)
    if todo:
        cluster = None
        if isinstance(scheduler, str) and scheduler == "local":
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        elif isinstance(scheduler, str):
            client = Client(scheduler)
        else:
            client = scheduler
        try:
            futures = []
            for c in todo:
                start, end = c * chunk, min((c + 1) * chunk, items)
                futures.append(client.submit(_run_chunk, study, c, start, end, jobs_per_task,
                                             key=f"gearpump-mc-{fingerprint}-{c}"))
            done = 0
            for fut in as_completed(futures):
                c, d = fut.result()
                _write_chunk(out, c, c * chunk * nc, d)
                done += 1
                if progress is not None:
                    progress(reused + done, nchunks)
        finally:
            if client is not scheduler:
                client.close()
            if cluster is not None:
                cluster.close()
    runs = _read_chunks(out, nchunks, plan["rows"])
    record = _gearpump.montecarlo_summarize(study, runs["eta_v"], runs["flow_lpm"],
                                            runs["torque_nm"])
    return {"record": record, "runs": runs, "chunks_computed": len(todo),
            "chunks_reused": reused, "out": str(out)}
