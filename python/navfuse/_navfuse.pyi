"""Type stubs of the Rust extension (src/*.rs). Call the functions of ``navfuse``
(navfuse/__init__.py), which make the DataFrames and result objects; these take plain
values and return dicts of columns (NumPy arrays, lists of str)."""

from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

Columns = Dict[str, Union[np.ndarray, List[Optional[str]]]]

__version__: str

def run(
    kind: str,
    value: str,
    base_dir: str,
    out: Optional[str] = None,
    outages: Optional[str] = None,
    smooth: bool = False,
    smooth_mode: Optional[str] = None,
    formats: Optional[str] = None,
) -> Tuple[Dict[str, Any], List[str]]:
    """kind: "path", "yaml-path" (KF-GINS), "toml" or "yaml" (text). Returns
    ({solution, imu_errors, states, smoothed, smoothed_states: Columns or None,
    innovations: Columns,
    summary_json, events_log: str}, config warnings). Releases the GIL; Ctrl-C stops
    the run cleanly."""

def simulate(kind: str, value: str, base_dir: str, out: str, seed: Optional[int] = None) -> str:
    """Generate the scenario into ``out``; returns sim_summary.json's text."""

def read_trajectory(path: str, format: str = "auto", quality: Sequence[int] = ...) -> Tuple[Columns, str, List[str]]: ...
def read_imu(kind: str, value: str, base_dir: str) -> Tuple[Columns, Optional[int]]:
    """kind: as run(), or "inputs" (TOML of [imu] / [gnss] keys alone)."""
def read_gnss(kind: str, value: str, base_dir: str) -> Tuple[Columns, Optional[int], List[str]]: ...
def read_rinex_obs(path: str) -> Tuple[Columns, List[str]]: ...
def evaluate(
    solution: Union[str, Dict[str, Any]],
    truth: Union[str, Dict[str, Any]],
    gaps: Optional[str] = None,
    lever_arm: Optional[Sequence[float]] = None,
    window: Optional[Tuple[float, float]] = None,
    solution_format: str = "auto",
    truth_format: str = "auto",
    quality: Sequence[int] = ...,
) -> Tuple[str, Columns]:
    """Returns (the `navfuse eval --json` report as text, the per-epoch errors)."""
def batch_cases(manifest: str) -> List[str]: ...
def batch_case(manifest: str, index: int, out: Optional[str] = None) -> Dict[str, Any]: ...
def batch(manifest: str, out: Optional[str] = None, jobs: int = 0, progress: bool = False) -> Tuple[List[Dict[str, Any]], List[float], float]: ...
