"""driftcorr: removes the drift from SLAM / odometry trajectories using the map of the place.

The compiled module ``_driftcorr`` is the C++ library (examples/pipeline) behind numpy arrays;
this package only gives its results names. Nothing is computed here.

Array layouts (float64, one row per pose):

- trajectory in its own frame (``trajectory``, ``ground_truth``, ``Correction.corrected``,
  ``Scenario.estimate``): ``(N, 8)`` ``t x y z qx qy qz qw`` (TUM: t [s] strictly increasing,
  position [m], unit quaternion T_frame_body), or ``(N, 4)`` ``t x y z`` without orientation;
- trajectory in the world plane, East-North-Up at the anchor (``*_en``): ``(N, 5)``
  ``t east north up yaw`` (yaw [rad] counter-clockwise from East), or ``(N, 4)`` without yaw;
- per-pose covariance (``covariance``): ``(N, 8)``
  ``t var_e cov_en var_n var_up var_yaw cov_e_yaw cov_n_yaw`` ([m^2], [rad^2], [m rad]);
- per-pose verdict flags (``flags``): ``(N,)`` uint8, bits 1 off the map, 2 input jump,
  4 implausible scale, 8 a height change the estimate denies, 16 a floor not determined,
  32 a turn the estimate does not make.

Errors: a bad argument (wrong shape, NaN, missing map file, unknown key) raises ``ValueError`` or
``TypeError`` whose message starts with the argument's name; a bad file raises
``driftcorr.InputError`` (a ``ValueError``) naming the file, line and key. A correction that
fails is not an exception: see ``Correction.status``, ``usable`` and ``verdict``.

Solves in one process run one at a time (the GIL is released meanwhile); to correct several
drives at once, use several processes (``python/examples/dask_correct.py``).
"""
from dataclasses import dataclass
from typing import List, Optional

import numpy as np

from . import _driftcorr
from ._driftcorr import InputError

__all__ = ["InputError", "Scenario", "Correction", "StreamPose", "StreamResult", "Stream",
           "load_scenario", "correct_scenario", "correct", "metrics"]


@dataclass(frozen=True)
class Scenario:
    """A scenario folder as read from its scenario.yaml (docs/FORMAT.md). ``anchor`` and ``map`` have
    the keys of the file's ``anchor:`` block and ``map:`` entries (paths resolved), so that
    ``correct(s.estimate, s.map, s.anchor, frame=s.frame, mode=s.mode)`` corrects it."""
    name: str
    path: str                          #: the scenario.yaml that was read
    mode: str                          #: road2d | indoor3d
    frame: str                         #: kitti_camera | enu
    anchor: dict
    map: List[dict]
    estimate: np.ndarray               #: (N, 8) or (N, 4), the trajectory's own frame
    ground_truth: Optional[np.ndarray]  #: same layout and timestamps, or None
    warnings: List[str]


@dataclass(frozen=True)
class Correction:
    """One batch correction (what ``driftcorr correct`` prints and writes)."""
    name: str
    mode: str
    frame: str
    status: str               #: the solver's outcome: success | acceptable | ... | failed
    message: str
    usable: bool              #: the solver produced a trajectory (corrected is not None)
    #: (N, 8) in the estimate's frame (for an estimate without orientation the orientation is the
    #: corrected heading alone); None if unusable
    corrected: Optional[np.ndarray]
    corrected_en: Optional[np.ndarray]  #: (N, 5) world plane; None if unusable
    estimate_en: np.ndarray             #: the input in the world plane (after the anchor)
    ground_truth_en: Optional[np.ndarray]
    covariance: Optional[np.ndarray]    #: (N, 8); None unless covariance_status == "ok"
    covariance_status: str
    covariance_message: str
    flags: np.ndarray                   #: (N,) uint8 verdict flags
    verdict: str                        #: ok | degraded | failed (judged without ground truth)
    reasons: List[str]
    scale_min: float                    #: corrected / estimated path per scale segment
    scale_max: float
    input_jumps: int
    off_map_share: float
    metrics_before: Optional[dict]      #: the estimate against ground truth (see metrics())
    metrics_after: Optional[dict]       #: the correction against ground truth
    warnings: List[str]
    anchor_yaw_deg: float               #: as given, or as estimated (yaw_deg: auto)
    anchor_origin_en: tuple
    global_scale: float                 #: the estimate's positions times it are metres (scale: auto)
    drive_scale: float                  #: global_scale times the corrected path over the scaled
                                        #: estimate's (NaN: no correction of its own written)
    drive_scale_sd: float               #: its standard deviation from the covariance (NaN: none)
    timings: dict                       #: load_s, map_s, solve_s
    windows: int
    iterations: int


@dataclass(frozen=True)
class StreamPose:
    """The causal estimate ``Stream.push`` returns for one pose."""
    index: int                #: index of the pose among the accepted ones
    pose: np.ndarray          #: (8,) t x y z qx qy qz qw, the input's frame
    pose_en: np.ndarray       #: (5,) t east north up yaw
    gap: bool                 #: the step took longer than online.gap_warn_s
    outside_map: bool         #: outside the map field: odometry only
    doubt: int                #: why the pose may be wrong, bits: 1 off the map, 2 a window in
                              #: a wrong basin, 4 an implausible scale, 8 hypotheses that part,
                              #: 16 a speed jump of the input within 10 s or with no
                              #: turn solved since (dropped steps), 32 the global
                              #: scale still searched (scale: auto; the input at the best
                              #: scale so far), 64 the first output after the chain was
                              #: re-localised from its prefix (it may jump), 128 the
                              #: newest solve moved the previous output outside its
                              #: 95 % region (the covariance holds the move)
    correction_age_epochs: int  #: epochs since the last pose of the solve it chains from
    correction_age_s: float     #: the same in stream seconds
    fresh: bool               #: it chains from the newest solve requested before the pose
    #: (7,) var_e cov_en var_n var_up var_yaw cov_e_yaw cov_n_yaw [m^2, rad^2, m rad], as the
    #: status column's (online.calibrate_covariance); None when not known
    covariance: Optional[np.ndarray]
    message: str


@dataclass(frozen=True)
class StreamResult:
    """The smoothed whole trajectory ``Stream.finish`` returns."""
    status: str
    message: str
    usable: bool
    poses: int
    corrected: Optional[np.ndarray]
    corrected_en: Optional[np.ndarray]
    covariance: Optional[np.ndarray]
    covariance_status: str
    covariance_message: str
    scale_min: float
    scale_max: float
    #: scale: auto: the global scale found (None: the anchor's scale), and how many outputs came
    #: before it (doubt 32)
    global_scale: Optional[float]
    outputs_before_scale: int
    warnings: List[str]
    #: ok | degraded | failed, as ``driftcorr stream`` judges it (the smoothed trajectory and the
    #: causal outputs against each other); None when not usable
    verdict: Optional[str]
    reasons: List[str]


def load_scenario(path) -> Scenario:
    """Reads a scenario folder (or its scenario.yaml) and its trajectories."""
    return Scenario(**_driftcorr.load_scenario(path))


def correct_scenario(path, config=None, solver: str = "driftcorr") -> Correction:
    """Corrects a scenario folder as ``driftcorr correct`` does. ``config``: None (defaults) or
    the path of a params.yaml; ``solver``: driftcorr | paper."""
    return Correction(**_driftcorr.correct_scenario(path, config, solver))


def correct(trajectory, map, anchor, *, frame: str, mode: str, ground_truth=None, config=None,
            solver: str = "driftcorr", name: str = "") -> Correction:
    """Corrects a trajectory held in memory.

    trajectory: (N, 8) or (N, 4) in its own frame (N >= 3).
    map: a layer file path, or a list of paths and dicts ``{path, format, role, floor_z_m, lifts}``
        (the keys of scenario.yaml's ``map:`` entries; format from the extension when absent).
    anchor: a dict with the keys of scenario.yaml's ``anchor:`` block: ``lat_deg``, ``lon_deg``
        [, ``alt_m``] or ``crs``, ``easting_m``, ``northing_m``; ``yaw_deg`` (a number or "auto",
        required), ``z_m`` (required in indoor3d), ``position_search_m``.
    frame: kitti_camera | enu;  mode: road2d | indoor3d (both required).
    ground_truth: optional, same layout and number of rows; fills the metrics.
    """
    return Correction(**_driftcorr.correct(trajectory, map, anchor, frame, mode, ground_truth,
                                           config, solver, name))


def metrics(trajectory_en, ground_truth_en) -> dict:
    """ATE, final, max, p90, mean error [m], KITTI drift [%], floor accuracy and path length of a
    world-plane trajectory against ground truth, pose by pose (docs/FORMAT.md, "Judging")."""
    return _driftcorr.metrics(trajectory_en, ground_truth_en)


class Stream:
    """The online corrector (``driftcorr stream``): ``push`` returns each pose's causal estimate
    at once, ``finish`` smooths the whole trajectory.

    ``Stream(scenario)`` takes the map, anchor and frame of a scenario folder;
    ``Stream(map=..., anchor=..., frame=..., mode=...)`` takes them as ``correct`` does.
    ``synchronous``: solve inside ``push`` (deterministic; that push takes as long as the solve);
    otherwise a worker thread solves in the background, as the CLI does.
    """

    def __init__(self, scenario=None, *, map=None, anchor=None, frame=None, mode=None,
                 config=None, synchronous: bool = False):
        if scenario is not None:
            given = [k for k, v in (("map", map), ("anchor", anchor), ("frame", frame),
                                    ("mode", mode)) if v is not None]
            if given:
                raise ValueError(f"scenario: give a scenario or map/anchor/frame/mode, "
                                 f"not both (also given: {', '.join(given)})")
            self._stream = _driftcorr.Stream.from_scenario(scenario, config, bool(synchronous))
        else:
            self._stream = _driftcorr.Stream.from_map(map, anchor, frame, mode, config,
                                                      bool(synchronous))

    def push(self, pose) -> StreamPose:
        """Adds the next pose, 8 values ``t x y z qx qy qz qw`` in the trajectory's frame. A
        rejected pose (NaN, wrong length, timestamp not after the previous one) raises
        ValueError naming ``pose`` and leaves the stream unchanged."""
        return StreamPose(**self._stream.push(pose))

    def finish(self) -> StreamResult:
        """Waits for queued solves and smooths the whole trajectory. Call once."""
        return StreamResult(**self._stream.finish())

    def __len__(self) -> int:
        return len(self._stream)
