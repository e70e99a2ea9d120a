"""navfuse from Python: GNSS/INS integrated navigation returning pandas DataFrames.

    import navfuse
    res = navfuse.run("examples/demo/drive_excerpt.toml")
    res.solution          # DataFrame, the columns of solution.csv (lat_deg, vn_mps, yaw_deg, std_*, state)
    res.summary["status"] # summary.json as a dict
    ev = navfuse.evaluate(res, "examples/demo/gnss.pos", lever_arm=(0, -0.05, 0))
    ev.stats["position_m"]["horizontal"]["rms"]

The work is done by the same Rust library as the ``navfuse`` command (``navfuse run``,
``navfuse sim``, ``navfuse eval``), with the GIL released. Column names carry their
units; see docs/PYTHON.md for every table.
"""

from __future__ import annotations

import json
import os
import re
import tempfile
import warnings as _warnings
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import pandas as pd

from . import _navfuse
from ._errors import (InputError, Interrupted, NavfuseError, NavfuseWarning, RunError,
                      UnreliableWarning)
from ._toml import dumps as _toml_dumps

__version__ = _navfuse.__version__

__all__ = [
    "run", "simulate", "evaluate", "batch", "batch_case", "batch_cases", "batch_table", "read_imu", "read_gnss", "read_rinex_obs",
    "read_nav", "read_trajectory", "RunResult", "SimResult", "EvalResult", "BatchResult",
    "NavfuseError", "InputError", "RunError", "Interrupted", "NavfuseWarning", "UnreliableWarning",
]

ConfigLike = Union[str, "os.PathLike[str]", Mapping[str, Any]]


def _frame(cols: Optional[Dict[str, Any]]) -> Optional[pd.DataFrame]:
    if cols is None:
        return None
    # The arrays are the frame's own (made for it in Rust): no copy.
    return pd.DataFrame(cols, copy=False)


def _config_arg(config: ConfigLike, base_dir: Union[str, "os.PathLike[str]", None],
                kf_gins: bool = False) -> Tuple[str, str, str]:
    """(kind, value, base_dir) for the extension: a path, TOML (or KF-GINS YAML) text,
    or a dict. A str is text when it has a line break, or an '=' (TOML) / ':' (YAML)
    and is not the name of a file; else a path."""
    base = os.fspath(base_dir) if base_dir is not None else os.getcwd()
    if isinstance(config, Mapping):
        return "toml", _toml_dumps(dict(config)), base
    if isinstance(config, os.PathLike):
        return ("yaml-path" if kf_gins else "path"), os.fspath(config), base
    if not isinstance(config, str):
        raise TypeError(f"config: expected a path, TOML text or a dict, found {type(config).__name__}")
    is_file_name = os.path.exists(config) or config.strip().lower().endswith((".toml", ".yaml", ".yml"))
    marker = ":" if kf_gins else "="
    if "\n" in config or (marker in config and not is_file_name):
        return ("yaml" if kf_gins else "toml"), config, base
    return ("yaml-path" if kf_gins else "path"), config, base


def _dict_error(e: InputError, toml_text: str) -> None:
    """An error in a dict config: its line is one of the TOML made from the dict, so
    say that line instead of pointing into text the caller never wrote."""
    if e.line is not None:
        lines = toml_text.splitlines()
        made = lines[e.line - 1] if 0 < e.line <= len(lines) else ""
        e.args = (f"{e.message} (in the configuration dict: `{made.strip()}`)",)
        e.message = e.args[0]
        e.file = "<config dict>"
        e.line = None


@dataclass
class RunResult:
    """What ``navfuse.run`` returns.

    solution:        one row per output epoch, the columns of ``solution.csv`` with its
                     values (9 decimals): gps_week, t_s, lat_deg, lon_deg, h_m, vn_mps,
                     ve_mps, vd_mps, roll_deg, pitch_deg, yaw_deg, the std_* columns
                     (with [output] std), gnss_integrity (with the monitor), state.
    imu_errors:      imu_err.txt as columns: gps_week, t_s, gyro bias b*_degph, accel
                     bias ba*_mgal, scale factors s*_ppm.
    states:          states.csv (extra filter states and their sd_*), or None.
    smoothed:        smoothed.csv when smoothing ran, else None.
    smoothed_states: smoothed_states.csv, or None.
    innovations:     innovations.csv at full precision: every update an aiding source
                     tried (t_s, source, rows, y1..y3 the first innovations, nis, gate,
                     outcome applied / rejected / singular).
    summary:         summary.json as a dict (status, counts, time offset, files, ...).
    events:          the lines of events.log.
    out:             the folder the files were written to (``out=``), or None.
    warnings:        the configuration's warnings (e.g. unknown KF-GINS keys).
    """

    solution: pd.DataFrame
    imu_errors: pd.DataFrame
    states: Optional[pd.DataFrame]
    smoothed: Optional[pd.DataFrame]
    smoothed_states: Optional[pd.DataFrame]
    innovations: pd.DataFrame
    summary: Dict[str, Any]
    events: List[str]
    out: Optional[Path]
    warnings: List[str] = field(default_factory=list)

    @property
    def status(self) -> str:
        return str(self.summary.get("status", ""))


def _run_result(d: Dict[str, Any], out: Optional[Path], warnings: List[str]) -> RunResult:
    empty = pd.DataFrame()
    return RunResult(
        solution=_frame(d["solution"]) if d["solution"] is not None else empty,
        imu_errors=_frame(d["imu_errors"]) if d["imu_errors"] is not None else empty,
        states=_frame(d["states"]),
        smoothed=_frame(d["smoothed"]),
        smoothed_states=_frame(d["smoothed_states"]),
        innovations=_frame(d["innovations"]),
        summary=json.loads(d["summary_json"]) if d["summary_json"] else {},
        events=d["events_log"].splitlines(),
        out=out,
        warnings=list(warnings),
    )


def run(config: ConfigLike, *, out: Union[str, "os.PathLike[str]", None] = None,
        outages: Optional[str] = None, smooth: bool = False, smooth_mode: Optional[str] = None,
        formats: Optional[str] = None, kf_gins: bool = False,
        base_dir: Union[str, "os.PathLike[str]", None] = None) -> RunResult:
    """Navigate, as ``navfuse run CONFIG`` does.

    config:   a path (navfuse .toml or KF-GINS .yaml), TOML text, or a dict of the TOML
              sections (``{"imu": {...}, "gnss": {...}}``); relative paths in text or a
              dict resolve against ``base_dir`` (default: the current directory).
    out:      also write the files of ``navfuse run --out OUT``.
    outages, smooth, smooth_mode, formats: as ``--outages``, ``--smooth``,
              ``--smooth-mode``, ``--formats``.
    kf_gins:  ``config`` is KF-GINS YAML text.

    Raises InputError (file, line, field) for bad inputs and option values, RunError when
    the run failed (``e.result``: what was computed before), KeyboardInterrupt on Ctrl-C:
    the forward run stops at the next epoch (smoothing, once under way, finishes first)
    and ``e.result`` holds what was computed; the files of ``out`` are complete up to
    that epoch. The configuration's warnings and the run's plausibility warnings
    (summary.json ``warnings``: units, axes, time scales, ...) are issued with
    ``warnings.warn`` as NavfuseWarning; a result the program can tell is meaningless
    (``status`` "unreliable", where ``navfuse run`` exits with 3) as UnreliableWarning,
    one per reason (summary.json ``unreliable``).
    """
    kind, value, base = _config_arg(config, base_dir, kf_gins)
    out_s = os.fspath(out) if out is not None else None
    out_p = Path(out_s) if out_s else None
    try:
        d, warnings = _navfuse.run(kind, value, base, out_s, outages, bool(smooth), smooth_mode,
                                   formats)
    except (RunError, InputError, Interrupted) as e:
        if isinstance(config, Mapping) and isinstance(e, InputError):
            _dict_error(e, value)
        if (kind in ("toml", "yaml") and base_dir is None and isinstance(e, InputError)
                and "cannot open" in str(e) and e.file and not os.path.exists(e.file)):
            e.args = (f"{e.message} (relative paths in a configuration given as text or a "
                      f"dict resolve against base_dir=, here the current directory {base})",)
            e.message = e.args[0]
        if e.partial is not None:
            e.result = _run_result(e.partial, out_p, [])
        raise
    except KeyboardInterrupt as e:
        partial = getattr(e, "result", None)
        if isinstance(partial, dict):
            e.result = _run_result(partial, out_p, [])
        raise
    res = _run_result(d, out_p, warnings)
    for w in list(warnings) + list(res.summary.get("warnings") or []):
        _warnings.warn(f"navfuse: {w}", NavfuseWarning, stacklevel=2)
    for w in res.summary.get("unreliable") or []:
        _warnings.warn(f"navfuse: unreliable: {w}", UnreliableWarning, stacklevel=2)
    return res


class _KeptPath(type(Path())):
    """A path that keeps the temporary folder it is in alive (``simulate()`` without
    ``out``): ``navfuse.run(navfuse.simulate(s).run_config)`` works."""

    _owner: Any = None


class SimResult:
    """What ``navfuse.simulate`` returns: the folder of ``navfuse sim`` and its tables,
    read when first used.

    dir, summary (sim_summary.json), run_config (the run.toml to navigate on it),
    truth (truth.nav: gps_week, t_s, lat_deg, ..., yaw_deg at the IMU rate),
    imu (t_s, dt_s, dtheta_*_rad, dvel_*_mps, as navfuse run reads it), gnss (the fixes,
    or for raw-measurement scenarios the single point fixes), events (events.csv),
    gnss_errors (gnss_errors.csv, when written). Without ``out=`` the folder is a
    temporary one, removed with this object.
    """

    def __init__(self, directory: Path, summary: Dict[str, Any],
                 tmp: Optional[tempfile.TemporaryDirectory] = None) -> None:
        self.dir = directory
        self.summary = summary
        self._tmp = tmp

    @property
    def run_config(self) -> Path:
        p = _KeptPath(self.dir / "run.toml")
        p._owner = self
        return p

    @cached_property
    def truth(self) -> pd.DataFrame:
        return read_nav(self.dir / "truth.nav")

    @cached_property
    def imu(self) -> pd.DataFrame:
        return read_imu(self.run_config)

    @cached_property
    def gnss(self) -> Optional[pd.DataFrame]:
        try:
            return read_gnss(self.run_config)
        except ValueError as e:
            if "no [gnss] section" in str(e):
                return None
            raise

    def _csv(self, name: str) -> Optional[pd.DataFrame]:
        p = self.dir / name
        return pd.read_csv(p) if p.exists() else None

    @cached_property
    def events(self) -> Optional[pd.DataFrame]:
        return self._csv("events.csv")

    @cached_property
    def gnss_errors(self) -> Optional[pd.DataFrame]:
        return self._csv("gnss_errors.csv")

    def __repr__(self) -> str:
        return f"SimResult(dir={str(self.dir)!r}, files={self.summary.get('files')})"


def simulate(scenario: Union[str, "os.PathLike[str]"], *, seed: Optional[int] = None,
             out: Union[str, "os.PathLike[str]", None] = None,
             base_dir: Union[str, "os.PathLike[str]", None] = None) -> SimResult:
    """Simulate a scenario (a path, or scenario TOML text), as ``navfuse sim``.

    seed: the random seed in place of the scenario's. out: the folder (default: a
    temporary one, kept as long as the result is).
    """
    kind, value, base = _config_arg(scenario, base_dir)
    tmp = None
    if out is None:
        tmp = tempfile.TemporaryDirectory(prefix="navfuse-sim-")
        out = tmp.name
    summary = _navfuse.simulate(kind, value, base, os.fspath(out), seed)
    return SimResult(Path(out), json.loads(summary), tmp)


@dataclass
class EvalResult:
    """What ``navfuse.evaluate`` returns: ``stats`` as ``navfuse eval --json`` prints
    it, ``errors`` as ``--errors`` writes it (full precision; NaN where a side lacks
    velocity or attitude)."""

    stats: Dict[str, Any]
    errors: pd.DataFrame

    def rms(self, what: str = "horizontal") -> float:
        """RMS of a position error: north, east, down, horizontal, vertical, 3d [m]."""
        return float(self.stats["position_m"][what]["rms"])


def _traj_arg(x: Any) -> Any:
    if isinstance(x, RunResult):
        x = x.solution
    elif isinstance(x, SimResult):
        x = x.truth
    if isinstance(x, pd.DataFrame):
        cols = {c: np.ascontiguousarray(x[c].to_numpy(dtype=np.float64))
                for c in ("t_s", "lat_deg", "lon_deg", "h_m", "vn_mps", "ve_mps", "vd_mps",
                          "roll_deg", "pitch_deg", "yaw_deg") if c in x.columns}
        if "gps_week" in x.columns and len(x) > 0 and "t_s" in cols:
            # Seconds from the first row's week (a track may cross a week).
            week = x["gps_week"].to_numpy(dtype=np.int64)
            cols["t_s"] = np.ascontiguousarray(cols["t_s"] + (week - week[0]) * 604800.0)
            cols["__week__"] = int(week[0])
        return cols
    return os.fspath(x)


def evaluate(solution: Any, truth: Any, *, gaps: Optional[str] = None,
             lever_arm: Optional[Sequence[float]] = None,
             window: Optional[Tuple[float, float]] = None, solution_format: str = "auto",
             truth_format: str = "auto", quality: Sequence[int] = (1,)) -> EvalResult:
    """Score a solution against a reference, as ``navfuse eval SOLUTION TRUTH``.

    Either side: a path (any format navfuse eval reads, recognised by content), a
    RunResult (its solution), a SimResult (its truth) or a DataFrame with t_s, lat_deg,
    lon_deg, h_m (optionally gps_week, vn/ve/vd_mps, roll/pitch/yaw_deg).
    gaps, lever_arm, window, quality: as --gaps, --lever-arm, --window, --quality.
    """
    la = None if lever_arm is None else [float(v) for v in lever_arm]
    w = None if window is None else (float(window[0]), float(window[1]))
    stats, errors = _navfuse.evaluate(_traj_arg(solution), _traj_arg(truth), gaps, la, w,
                                      solution_format, truth_format, list(quality))
    return EvalResult(json.loads(stats), _frame(errors))


def read_trajectory(path: Union[str, "os.PathLike[str]"], format: str = "auto",
                    quality: Sequence[int] = (1,)) -> pd.DataFrame:
    """Any trajectory navfuse eval reads (.nav, solution.csv, RTKLIB .pos, KF-GINS GNSS
    text, PX4 ULog), its format recognised by content unless named: gps_week, t_s,
    lat_deg, lon_deg, h_m and, when the file has them, vn/ve/vd_mps, roll/pitch/yaw_deg."""
    cols, fmt, warnings = _navfuse.read_trajectory(os.fspath(path), format, list(quality))
    df = _frame(cols)
    df.attrs["format"] = fmt
    df.attrs["warnings"] = warnings
    return df


def read_nav(path: Union[str, "os.PathLike[str]"]) -> pd.DataFrame:
    """A KF-GINS-style ``.nav`` file (solution.nav, truth.nav)."""
    return read_trajectory(path, "nav")


def _reader_arg(config: ConfigLike, section: str, keys: Dict[str, Any],
                base_dir: Union[str, "os.PathLike[str]", None], kf_gins: bool) -> Tuple[str, str, str]:
    """A run configuration (path, text, dict), or a data file with its section's keys
    (``read_imu("imu.txt", format="kf-gins", rate_hz=200)``)."""
    if isinstance(config, (str, os.PathLike)) and not isinstance(config, Mapping):
        p = os.fspath(config)
        is_config = p.strip().lower().endswith((".toml", ".yaml", ".yml")) or "\n" in p
        if keys or not is_config:
            base = os.fspath(base_dir) if base_dir is not None else os.getcwd()
            return "inputs", _toml_dumps({section: {"file": p, **keys}}), base
    if keys:
        raise TypeError(f"[{section}] keys are given with a data file, not with a configuration")
    return _config_arg(config, base_dir, kf_gins)


def _call_reader(f: Any, kind: str, value: str, base: str, section: str) -> Any:
    """A reader call; an error in the keywords (not in a file) names the keyword."""
    try:
        return f(kind, value, base)
    except InputError as e:
        if kind == "inputs" and (e.file or "").endswith("<reader keys>"):
            key = e.field or ""
            key = key[len(section) + 1:] if key.startswith(section + ".") else key
            msg = re.sub(r"^.*?<reader keys>(:\d+)?: (key '[^']*': )?", "", e.message)
            e.args = (f"read_{section}: keyword {key!r}: {msg}",)
            e.message, e.file, e.line, e.field = e.args[0], None, None, key
        raise


def read_imu(config: ConfigLike, *, base_dir: Union[str, "os.PathLike[str]", None] = None,
             kf_gins: bool = False, **imu_keys: Any) -> pd.DataFrame:
    """An IMU file, read as navfuse run reads it (format, units, axes, time offset):
    either the ``[imu]`` of a run configuration (a path, text or a dict), or a data file
    with the ``[imu]`` keys of docs/CONFIG.md as keywords:
    ``read_imu("imu.txt", format="kf-gins", rate_hz=200)``,
    ``read_imu("imu.csv", format="csv", rate_hz=100, csv={"time_col": 0, ...})``.
    Columns: t_s, dt_s, dtheta_{x,y,z}_rad, dvel_{x,y,z}_mps (increments over each
    interval ending at t_s). ``df.attrs["gps_week"]``: the week."""
    kind, value, base = _reader_arg(config, "imu", imu_keys, base_dir, kf_gins)
    cols, week = _call_reader(_navfuse.read_imu, kind, value, base, "imu")
    df = _frame(cols)
    df.attrs["gps_week"] = week
    return df


def read_gnss(config: ConfigLike, *, base_dir: Union[str, "os.PathLike[str]", None] = None,
              kf_gins: bool = False, **gnss_keys: Any) -> pd.DataFrame:
    """GNSS fixes, read as navfuse run reads them: the ``[gnss]`` of a run configuration,
    or a data file with the ``[gnss]`` keys as keywords
    (``read_gnss("rover.pos", format="rtklib-pos", quality=[1, 2])``). KF-GINS text,
    .pos, NMEA, CSV, ULog, UBX; RINEX and UBX raw: the single point fixes. Columns:
    t_s, lat_deg, lon_deg, h_m, std_{n,e,d}_m, v{n,e,d}_mps, std_v{n,e,d}_mps (NaN
    without velocity)."""
    kind, value, base = _reader_arg(config, "gnss", gnss_keys, base_dir, kf_gins)
    cols, week, warnings = _call_reader(_navfuse.read_gnss, kind, value, base, "gnss")
    df = _frame(cols)
    df.attrs["gps_week"] = week
    df.attrs["warnings"] = warnings
    return df


def read_rinex_obs(path: Union[str, "os.PathLike[str]"]) -> pd.DataFrame:
    """Every observation of a RINEX 2/3/4 observation file (plain, .gz, Hatanaka), one
    row per epoch, satellite and code: gps_week, t_s, flag, sat (G05), code (C1C),
    value, lli, ssi."""
    cols, warnings = _navfuse.read_rinex_obs(os.fspath(path))
    df = _frame(cols)
    df.attrs["warnings"] = warnings
    return df


@dataclass
class BatchResult:
    """What ``navfuse.batch`` returns: ``table`` (one row per case in manifest order,
    the columns of batch.csv: index, name, seed, status, epochs, the figures, error),
    each case's wall time ``wall_s`` and the batch's ``total_wall_s`` [s]."""

    table: pd.DataFrame
    wall_s: List[float]
    total_wall_s: float

    @property
    def failed(self) -> int:
        return int((self.table["status"] != "completed").sum())


def batch_cases(manifest: Union[str, "os.PathLike[str]"]) -> List[str]:
    """The case names of a batch manifest (docs/CONFIG.md "Batch manifest"), in order."""
    return _navfuse.batch_cases(os.fspath(manifest))


def batch_case(manifest: Union[str, "os.PathLike[str]"], index: int, *,
               out: Union[str, "os.PathLike[str]", None] = None) -> Dict[str, Any]:
    """Case ``index`` of a manifest, as ``navfuse batch`` computes it (its run written
    to ``out/<name>`` with ``out``): the row of batch.csv as a dict. A failed case is a
    row with status "failed" and its error, not an exception."""
    return _navfuse.batch_case(os.fspath(manifest), int(index),
                               None if out is None else os.fspath(out))


def batch_table(rows: Sequence[Mapping[str, Any]]) -> pd.DataFrame:
    """Rows of ``batch_case`` (in any order) as the combined table, in case order."""
    rows = sorted(rows, key=lambda r: r["index"])
    return pd.DataFrame(list(rows))


def batch(manifest: Union[str, "os.PathLike[str]"], *, out: Union[str, "os.PathLike[str]", None] = None,
          jobs: Optional[int] = None, progress: bool = False) -> BatchResult:
    """``navfuse batch MANIFEST --jobs N``: every case on a thread pool in this process
    (``jobs``: default the number of cores). With ``out`` the case folders and
    batch.csv / batch.json / batch_timing.csv are written. The rows are the same
    whatever ``jobs``. Ctrl-C: no more cases are started, those under way finish, the
    tables are written, and KeyboardInterrupt is raised with ``e.result`` (the others
    "not run")."""
    if jobs is not None and int(jobs) < 1:
        raise ValueError(f"jobs: expected at least 1, found {jobs}")
    # 0: the CPUs this process may use, as the CLI's default.
    try:
        rows, wall, total = _navfuse.batch(os.fspath(manifest),
                                           None if out is None else os.fspath(out),
                                           0 if jobs is None else int(jobs), progress)
    except KeyboardInterrupt as e:
        r = getattr(e, "result", None)
        if isinstance(r, tuple):
            e.result = BatchResult(batch_table(r[0]), list(r[1]), float(r[2]))
        raise
    return BatchResult(batch_table(rows), list(wall), float(total))
