"""Laser mapping with keyframe landmarks, loop closure and a pose-graph solve.

Seed 002 §2.3 (Fig. 5): the map is a list of *laser landmarks*, each the
global pose at which it was added plus its pre-processed scan. For every new
scan the robot's pose is predicted by dead reckoning (seed 002 eqs. 1–5),
the scan is matched by ICP against the nearest landmarks (eqs. 6–8 relate
the relative pose (Δx_n, Δy_n, Δθ_n) to landmark n's pose), and the two are
fused by a Kalman update (eqs. 11–14 with the landmark poses held fixed:
x = x̂ + K (z − x̂), K = P̂ (P̂ + R)⁻¹, P = (I − K) P̂). A new landmark is added
when none of the recent landmarks is near the estimate.

Beyond the seed, the paper's joint robot-and-landmark EKF is replaced by a
pose graph, which holds the same information (every landmark pose and the
relative-pose constraints between them) and can be re-solved after a loop
closure:

- nodes: one pose per scan; edges: the fused relative pose between
  consecutive scans (information = inverse of the fused covariance), and
  loop-closure edges;
- the scan match is fused only when it passes an innovation test against
  the prediction, ν = z − x̂, νᵀ (P̂ + R)⁻¹ ν ≤ ``match_gate_chi2`` (3 dof):
  a fit far outside both spreads is ICP sliding along a corridor, and dead
  reckoning stands for that step; the match's fallback search widens with
  the odometry turn (``icp_window_theta_per_rad``), and on a large turn
  (``search_turn_rad``) it runs whether ICP fitted or not, the fit with more
  inliers kept: a turn's odometry error can leave ICP in a rival minimum; a
  fit under ``min_inlier_fraction`` is a partial overlap, fused by
  partial_overlap.py's rules (enough points, free directions, learnt noise);
- P̂, the odometry step's covariance (odometry_noise.py): by default a fixed
  σ_θ = 6 % of the turn + 0.02 rad/m + 0.5° (3–5 times the logs' calibrated
  error; the consistent ``learnt`` model did not make better maps);
- ``submap`` (on): each ICP fit is searched round and refined on a smoothed
  grid of the same local landmarks (submap_match.py: Olson's search, the
  grid fit after Hess et al. 2016, Olson's covariance; edmonton's per-match
  heading error 0.67° → 0.38° rms); ``submap_spread`` (off) adds the
  submap's own uncertainty (match_covariance.py, 3.); where the grid fit
  and ICP's part by d (the same scan on the same keyframes, so an error of
  the match its Hessian covariance does not see: on the station the steps
  0.15–0.2° off were those whose fits parted), ``match_disagreement_k``
  (1.5) adds k² d dᵀ to the match's covariance, and ``match_disagreement``
  says where it goes (by default, match_mixture.py: the match is the two
  fits' PDAF-weighted mean, the term eased by β_g β_i);
- loop closure (loop_closure.py): candidates by view overlap within a
  radius that grows with the graph path to each old landmark, verification
  by ICP and a correlative search over a window as wide as the drift (or,
  with ``loop.matcher`` "submap" / "both", against a submap of the
  candidate's keyframes: a correlative search over at least ±1 m / ±10°,
  the grid fit, Olson's covariance; at most ``loop.submap_per_step`` places
  per scan; on edmonton it closed the same places and the map came out
  worse, so ICP stays the default),
  a direction that only a few of the match's points hold is left free in
  the closure's edge (``free_directions``); strong closures accepted at
  once, weak ones only when a second closure agrees round their cycle and
  the graph's current estimate agrees too; ``final_pass`` in ``finish`` matches every
  landmark again against the solved map (by the local step's grid fit,
  ``loop.final_matcher``), and then (``long_range``,
  long_range.py) against whole earlier regions of it, 30 m of path or more
  back and up to 25 m away, where a large hall's far walls tie a stretch no
  loop closes (edmonton's start to its pass 100 m later); last, the edge
  classes' variance components and a solve (variance_components.py);
  ``final_rounds`` (1) runs all three again from the solved poses, each
  round replacing the last one's edges;
- solve: Gauss-Newton on the sparse normal equations (scipy.sparse, sparse
  LU), with a Cauchy loss by iteratively re-weighted least squares on the
  residuals whitened by each edge's square-root information; node 0 fixed;
  every edge's covariance has a floor (``edge_floor_*``): the matches'
  Hessian covariance does not see wrong pairings, and an edge trusted to a
  tenth of a degree would hold a loop closure off.

Bounded work per scan: compiled scan matches (icp_kernel.py) on bucketed
references; the online solve spread over the following scans
(``solve_iterations_per_step``); at most ``loop.candidates`` places verified
per new landmark, one correlative search per ``loop_search_every_m``.
``finish`` (once per log) solves to the end, the final pass and the ties
(2–7 s of CPU on the logs). The options are in mapping_config.py.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .ekf_slam import LandmarkEkf
from .icp import Reference, match, scan_normals, stacked_reference
from .long_range import long_range_ties
from .loop_closure import (
    Closure,
    ViewOverlap,
    agrees_with_graph,
    consistent,
    drift_window,
    final_pass,
    graph_path_m,
    rank_candidates,
    verify,
    verify_submap,
)
from .mapping_config import MappingConfig
from .match_covariance import fused_step, submap_spread
from .match_mixture import association_weights, mixture_measurement
from .odometry_calibration import OdometryCalibration
from .odometry_noise import OdometryNoise
from .partial_overlap import PartialOverlap
from .pose_graph import Edge, _sqrt_info, _whitened, gauss_newton, solve_pose_graph
from .se2 import compose, relative, wrap, wrap_pose
from .submap_match import Submap, SubmapCache, match_submap
from .variance_components import edge_classes, reweighted_solve

log = logging.getLogger(__name__)
_DEFAULT = MappingConfig()  # frozen: one instance serves as every default


@dataclass
class Landmark:
    node: int
    points: np.ndarray  # pre-processed scan, sensor frame
    normals: np.ndarray  # each point's line normal within this scan (icp.scan_normals)
    planar: np.ndarray  # ...and whether its neighbourhood is line-like

    @classmethod
    def of(cls, node: int, points: np.ndarray, neighbours: int) -> Landmark:
        return cls(node, points, *scan_normals(points, neighbours))


class LaserMapper:
    """Incremental laser mapping; ``add_scan`` per scan, ``poses`` at any time."""

    def __init__(self, cfg: MappingConfig = _DEFAULT) -> None:
        self.cfg = cfg
        self.poses: list[np.ndarray] = []
        self.path_m: list[float] = []  # odometry path length at each node
        self.landmarks: list[Landmark] = []
        self.edges: list[Edge] = []
        self.loop_closures = 0
        self.loop_rejected = 0
        self.loop_inconsistent = 0  # weak closures the graph's own estimate refuted
        self.icp_failures = 0
        self.match_rejected = 0  # fits refused by the innovation test
        self.partial_matches = 0  # fits under the inlier share fused (partial_overlap.py)
        self.final_closures = 0  # edges added by the final pass
        self.long_range_ties = 0  # ...and by the long-range ties (long_range.py)
        self.class_factors = np.ones(0)  # the edge classes' variance factors, if estimated
        self._odom_prev: np.ndarray | None = None
        self._ref_key: tuple = ()
        self._ref: Reference | None = None
        self._submaps = SubmapCache(cfg.grid_cfg("local"))
        self._since_closure_m = 0.0
        self._pending_solve = False
        self._solving = False  # an online solve is in progress (spread over steps)
        self._last_search_m = -math.inf
        self._pending: list[Closure] = []  # weak closures waiting for a partner
        self._accepted: list[Closure] = []
        self._overlap = ViewOverlap()
        nc = cfg.odometry_noise
        self.calibration = OdometryCalibration(gain_sigma=nc.gain_sigma, per_m_sigma=nc.per_m_sigma,
                                               scale_rel_sigma=nc.scale_rel_sigma)
        self.noise = OdometryNoise(nc)
        self.partial = PartialOverlap(cfg.partial, nc, cfg.min_inlier_fraction, cfg.icp)
        self.match_downweighted = 0  # matches whose heading disagreed with odometry
        self.ekf = LandmarkEkf() if cfg.backend == "ekf" else None
        self._ekf_index: dict[int, int] = {}  # landmark node -> EKF landmark number
        self._anchor: dict[int, tuple[int, np.ndarray]] = {}
        # each node's fused step covariance (world frame, no floor): what the
        # submap's own uncertainty is built from (match_covariance.submap_spread)
        self.step_covs: list[np.ndarray] = []

    # -- dead reckoning noise (seed 002 eqs. 2–5; odometry_noise.py) ------------------
    def odom_covariance(self, u: np.ndarray) -> np.ndarray:
        return self.noise.covariance(u, self.calibration if self.cfg.calibrate_odometry
                                     else None)

    def _local_reference(self) -> Reference:
        recent = self.landmarks[-self.cfg.local_landmarks:]
        key = tuple((lm.node, *self.poses[lm.node]) for lm in recent)
        if key != self._ref_key:
            self._ref = self._stack(recent)
            self._ref_key = key
        return self._ref

    def _local_submap(self) -> Submap:
        """The same landmarks as ``_local_reference``, rendered as a grid."""
        return self._submaps.get([(lm.node, self.poses[lm.node], lm.points)
                                  for lm in self.landmarks[-self.cfg.local_landmarks:]])

    def _stack(self, landmarks: list[Landmark]) -> Reference:
        """The landmarks' scans at their poses as one reference, each point
        with its own scan's normal (icp.scan_normals)."""
        return stacked_reference([(self.poses[lm.node], lm.points, lm.normals, lm.planar)
                                  for lm in landmarks], self.cfg.icp.normal_neighbours,
                                 self.cfg.icp.bucket_m, self.cfg.faces)

    def add_scan(self, odom_pose, points: np.ndarray) -> np.ndarray:
        """Add one scan (odometry pose, pre-processed points in the sensor
        frame); returns the current estimate of its pose."""
        odom = np.asarray(odom_pose, float)
        k = len(self.poses)
        if k == 0:
            self.poses.append(np.zeros(3))
            self.step_covs.append(np.zeros((3, 3)))
            self.path_m.append(0.0)
            self._odom_prev = odom
            self.landmarks.append(Landmark.of(0, points, self.cfg.icp.normal_neighbours))
            if self.ekf is not None:
                self._ekf_index[0] = self.ekf.add_landmark()
            return self.poses[0]
        u = relative(self._odom_prev, odom)
        self._odom_prev = odom
        step_m = math.hypot(u[0], u[1])
        self.path_m.append(self.path_m[-1] + step_m)
        self._since_closure_m += step_m
        prev = self.poses[-1]
        uc = self.calibration.correct(u)
        pred = compose(prev, uc)
        q = self.odom_covariance(u)
        if self.ekf is not None:
            self.ekf.predict(uc, q)
        est, cov = pred, q
        # the search window widens with the turn: odometry's turn error grows with it
        r = match(points, self._local_reference(), pred, self.cfg.icp,
                  self.cfg.icp_window_xy_m,
                  self.cfg.icp_window_theta_rad + self.cfg.icp_window_theta_per_rad * abs(u[2]),
                  self.cfg.min_inlier_fraction, abs(u[2]) > self.cfg.search_turn_rad)
        scale, spread, d = self.cfg.cov_scale(), 0.0, None
        good = r.inlier_fraction >= self.cfg.min_inlier_fraction
        partial = not good and self.partial.accepts(r, len(points))  # partial_overlap.py
        if self.cfg.submap and (good or partial):
            r, scale, spread, d = self._submap_refined(points, r)
        k2 = self.cfg.match_disagreement_k ** 2
        dis = 0.0 if d is None else k2 * np.outer(d, d)
        rc_fit = r.covariance * scale + spread + np.diag([1e-6, 1e-6, 1e-8])
        cal, qf = self.calibration if self.cfg.calibrate_odometry else None, q
        if partial:  # its covariance and the odometry noise it is weighed against
            rc_fit, qf = self.partial.weigh(points, self._local_reference(), r, rc_fit, u, q,
                                            cal)
        rc = rc_fit + dis  # with d
        innov = wrap_pose(r.pose - pred)
        if d is not None and self.cfg.match_disagreement == "mixture":
            # the two fits weighed as the PDAF weighs its measurements (match_mixture.py)
            beta = association_weights(innov, innov - d, qf + rc_fit)
            r.pose, rc = mixture_measurement(r.pose, rc_fit, d, beta, k2)
            innov = wrap_pose(r.pose - pred)
        if good:  # the turn's residual teaches the noise level (before any gate)
            res = float(wrap(relative(prev, r.pose)[2] - uc[2]))
            self.noise.learn(u, res, rc[2, 2], cal)
            self.partial.learn(u, res, rc[2, 2], cal)
            m2 = innov[2] ** 2 / (q[2, 2] + rc[2, 2])
            if m2 > self.cfg.match_heading_k ** 2:
                rc = rc * (m2 / self.cfg.match_heading_k ** 2)
                self.match_downweighted += 1
        if partial:
            rc = self.partial.huber(innov, qf, rc)
        fuse = good or partial
        if fuse and float(innov @ np.linalg.solve(qf + rc, innov)) > self.cfg.match_gate_chi2:
            # a fit far outside what odometry and the match's own spread allow:
            # ICP slid along a corridor or into a rival minimum; dead reckoning stands
            fuse = good = False
            self.match_rejected += 1
        if fuse:
            self.partial_matches += int(partial)
            gain, cov = fused_step(qf, rc_fit, rc, d, self.cfg.match_disagreement,
                                   self.cfg.match_gate_chi2)  # seed 002 eq. 13 form
            est = pred + gain @ innov
            est[2] = float(wrap(est[2]))
            if self.ekf is not None:  # seed 002: the match relative to the nearest landmark
                est = self._ekf_update_nearest(pred, r.pose, rc)
            if self.cfg.calibrate_odometry and good:
                rf = _in_frame(prev, rc)
                self.calibration.learn(u, relative(prev, r.pose), rf,
                                       self.noise.level * self.noise.random_var(u) + rf[2, 2])
        else:
            self.icp_failures += 1
        self.poses.append(est)
        self.step_covs.append(cov)
        if self.ekf is not None:
            anchor = self.landmarks[-1].node
            self._anchor[k] = (anchor, relative(self.poses[anchor], est))
        # consecutive-node edge: the fused step, in the previous node's frame
        z = relative(prev, est)
        c, s = math.cos(prev[2]), math.sin(prev[2])
        rot = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
        self.edges.append(Edge(k - 1, k, z, _sqrt_info(rot @ cov @ rot.T + self._floor())))
        verified = False
        if self._needs_landmark(est):
            self.landmarks.append(Landmark.of(k, points, self.cfg.icp.normal_neighbours))
            if self.ekf is not None:
                self._ekf_index[k] = self.ekf.add_landmark()
            if self.cfg.loop_closure:
                verified = self._try_loop_closure(k, points)
        if self._solving:
            self._solve_step(1 if verified else self.cfg.solve_iterations_per_step)
        return self.poses[-1]

    def _submap_refined(self, points: np.ndarray, r):
        """The ICP fit ``r`` searched round and refined on the local submap
        (submap_match.py); ICP's inlier share and (unless
        ``submap_covariance``) its covariance are kept. Returns the fit, the
        factor its covariance takes (``MappingConfig.cov_scale``) and the
        submap's own uncertainty to add (``submap_spread``, unscaled; 0
        when off) and the matchers' disagreement d (grid fit ⊖ ICP's; None
        without a grid fit)."""
        c = self.cfg
        s = match_submap(points, self._local_submap(), r.pose, c.submap_window_xy_m,
                         c.submap_window_theta_rad)
        if not s.converged:
            return r, c.cov_scale(), 0.0, None
        d = np.asarray(s.pose, float) - r.pose  # the two matchers' disagreement
        d[2] = 0.0 if c.match_disagreement == "position" else float(wrap(d[2]))
        r.pose = s.pose
        if c.submap_covariance:
            r.covariance = s.covariance
        return r, c.cov_scale(c.submap_covariance), self.submap_spread(s.pose), d

    def submap_spread(self, pose, part: str | None = None):
        """The local submap's own uncertainty at ``pose`` (match_covariance.py,
        3.): its keyframes' fused steps, anchored at the newest; ``part``
        defaults to ``MappingConfig.submap_spread`` ("off": 0)."""
        part = part or self.cfg.submap_spread
        if part == "off":
            return 0.0
        nodes = [lm.node for lm in self.landmarks[-self.cfg.local_landmarks:]]
        return submap_spread(pose[:2], nodes[-1], nodes, self.poses, self.step_covs, part)

    def _floor(self) -> np.ndarray:
        c = self.cfg
        return np.diag([c.edge_floor_xy_m ** 2, c.edge_floor_xy_m ** 2,
                        c.edge_floor_theta_rad ** 2])

    def _needs_landmark(self, pose: np.ndarray) -> bool:
        for lm in self.landmarks[-self.cfg.local_landmarks:]:
            p = self.poses[lm.node]
            if math.hypot(*(pose[:2] - p[:2])) < self.cfg.landmark_dist_m and \
                    abs(float(wrap(pose[2] - p[2]))) < self.cfg.landmark_angle_rad:
                return False
        return True

    # -- loop closure (loop_closure.py: candidates, verification, consistency) ------
    def _try_loop_closure(self, k: int, points: np.ndarray) -> bool:
        """Verify the best candidates for node k; True when any was verified."""
        c, lc = self.cfg, self.cfg.loop
        if self._since_closure_m < c.loop_every_m:
            return False  # just closed: the next closure can wait a little
        here = self.poses[k]
        self._pending = [p for p in self._pending
                         if self.path_m[k] - self.path_m[p.new] <= lc.pending_m]
        old = [i for i, lm in enumerate(self.landmarks)
               if self.path_m[k] - self.path_m[lm.node] > lc.min_separation_m]
        if not old:
            return False
        olds = [(self.landmarks[i].node, self.poses[self.landmarks[i].node],
                 self.landmarks[i].points) for i in old]
        drift = graph_path_m(np.asarray(self.path_m), k, np.array([o[0] for o in olds]),
                             [(c.old, c.new) for c in self._accepted])
        radius = np.array([drift_window(lc, d)[0] for d in drift])
        candidates = rank_candidates(here, points, olds, radius, self._overlap, lc)
        if lc.matcher == "submap":  # each costs a grid and a wide search: the best few
            candidates = candidates[:lc.submap_per_step]
        submaps = 0
        for n in candidates:
            _, win_xy, win_th = drift_window(lc, float(drift[n]))
            group = [self.landmarks[i] for i in old[max(0, n - lc.neighbours):
                                                    n + lc.neighbours + 1]]
            g, by_submap = None, False
            if lc.matcher != "submap":
                may_search = self.path_m[k] - self._last_search_m >= c.loop_search_every_m
                r, g, searched = verify(points, self._stack(group), here, win_xy, win_th,
                                        c.icp, lc, may_search)
                if searched:
                    self._last_search_m = self.path_m[k]
            if g is None and lc.matcher != "icp" and submaps < lc.submap_per_step:
                submaps += 1
                sub = Submap([(self.poses[lm.node], lm.points) for lm in group],
                             c.grid_cfg("closure"))
                r, g = verify_submap(points, sub, here, win_xy, win_th, lc)
                by_submap = True
            if g is None:
                continue
            node = olds[n][0]
            cov = _in_frame(self.poses[node], r.covariance * c.cov_scale(by_submap)) \
                + self._floor()
            cl = Closure(node, k, relative(self.poses[node], r.pose), cov, g == "strong",
                         r.inlier_fraction)
            if not cl.strong and self.ekf is not None:
                continue  # the EKF takes strong closures only (one linearisation, no undo)
            if not cl.strong and not agrees_with_graph(cl, self.poses, float(drift[n]), lc):
                self.loop_inconsistent += 1
                continue
            if not cl.strong:
                partners = [p for p in self._pending + self._accepted[-5:]
                            if p.new != k or p.old != node]
                agree = [p for p in partners if consistent(cl, p, self.poses, self.path_m, lc)]
                if not agree:
                    self._pending.append(cl)
                    continue
                for p in agree:
                    if p in self._pending:
                        self._pending.remove(p)
                        self._add_closure(p)
            self._add_closure(cl)
            break
        return bool(candidates)

    def _add_closure(self, cl: Closure) -> None:
        self.edges.append(Edge(cl.old, cl.new, cl.z, _sqrt_info(cl.cov), loop=True))
        self._accepted.append(cl)
        self.loop_closures += 1
        self._since_closure_m = 0.0
        if self.ekf is not None:  # the cross-covariances spread the correction
            if cl.old in self._ekf_index:
                self.ekf.update(self._ekf_index[cl.old], cl.z, cl.cov)
                self._ekf_sync()
            return
        implied = compose(self.poses[cl.old], cl.z)
        shift = math.hypot(*(implied[:2] - self.poses[cl.new][:2]))
        log.debug("loop closure %d -> %d (%s), correction %.2f m", cl.old, cl.new,
                  "strong" if cl.strong else "weak", shift)
        if shift > self.cfg.solve_min_correction_m or \
                abs(float(wrap(implied[2] - self.poses[cl.new][2]))) > 0.02:
            self._solving = True  # solved over the next steps (_solve_step)
        else:
            self._pending_solve = True

    # -- pose graph -----------------------------------------------------------------
    def _solve_step(self, iterations: int) -> None:
        """Part of the online solve: a few Gauss-Newton iterations from the
        current poses (new nodes join as they come); when it has converged,
        loop edges left far off are dropped as in ``optimise`` and the solve
        goes on without them."""
        x, done = gauss_newton(np.array(self.poses), self.edges, iterations,
                               tol=self.cfg.solve_tol)
        self.poses = list(x)
        if not done:
            return
        bad = [e for e in self.edges if e.loop and _whitened(e, x) > self.cfg.prune_sigma]
        if bad:
            self.loop_rejected += len(bad)
            self.edges = [e for e in self.edges if not any(e is b for b in bad)]
            return
        self._solving = False
        self._pending_solve = False

    def optimise(self) -> None:
        """Re-solve all node poses from the edges (see the module docstring).
        A loop-closure edge that the solution still leaves far off (whitened
        residual above ``prune_sigma``, where the Cauchy loss has all but
        ignored it) is taken for a false match: it is dropped and the graph
        solved again."""
        x = solve_pose_graph(np.array(self.poses), self.edges)
        bad = [e for e in self.edges if e.loop and _whitened(e, x) > self.cfg.prune_sigma]
        if bad:
            self.loop_rejected += len(bad)
            self.edges = [e for e in self.edges if not any(e is b for b in bad)]
            x = solve_pose_graph(np.array(self.poses), self.edges)
        self.poses = list(x)
        self._pending_solve = False
        self._solving = False

    # -- seed 002's landmark EKF as the back end ------------------------------------------
    def _ekf_update_nearest(self, pred: np.ndarray, icp_pose: np.ndarray,
                            icp_cov: np.ndarray) -> np.ndarray:
        recent = self.landmarks[-self.cfg.local_landmarks:]
        near = min(recent, key=lambda lm: math.hypot(*(self.poses[lm.node][:2] - pred[:2])))
        xn = self.poses[near.node]
        self.ekf.update(self._ekf_index[near.node], relative(xn, icp_pose), _in_frame(xn, icp_cov))
        self._ekf_sync()
        return self.ekf.robot

    def _ekf_sync(self) -> None:
        """Landmark nodes take their EKF poses; other nodes follow their anchor."""
        for node, idx in self._ekf_index.items():
            self.poses[node] = self.ekf.landmark(idx)

    def finish(self) -> np.ndarray:
        if self.ekf is not None:
            self._ekf_sync()
            for node, (anchor, rel) in self._anchor.items():
                if node not in self._ekf_index:
                    self.poses[node] = compose(self.poses[anchor], rel)
            return np.array(self.poses)
        if self._pending_solve or self._solving or any(e.loop for e in self.edges):
            self.optimise()
        if self.cfg.final_pass and self.cfg.loop_closure:
            online = list(self.edges)  # steps and online closures, as found while driving
            for _ in range(max(1, self.cfg.final_rounds)):
                self.edges = list(online)  # a later round replaces the last one's edges
                self._final_round()
        return np.array(self.poses)

    def _final_round(self) -> None:
        """The final pass, the long-range ties and the edge classes' variance
        components, from the current poses (``finish``)."""
        done = {(e.i, e.j) for e in self.edges if e.loop}
        extra = final_pass(np.array(self.poses), np.asarray(self.path_m),
                           [(lm.node, lm.points, lm.normals, lm.planar)
                            for lm in self.landmarks], done,
                           self.cfg.icp, self.cfg.loop, self._overlap,
                           self.cfg.cov_scale(self.cfg.loop.final_matcher == "submap"),
                           self._floor(), self.cfg.grid_cfg("final"), self.cfg.faces)
        for cl in extra:
            self.edges.append(Edge(cl.old, cl.new, cl.z, _sqrt_info(cl.cov), loop=True))
        self.final_closures = len(extra)
        if extra:
            self.optimise()
        if self.cfg.long_range:
            ties = long_range_ties(np.array(self.poses), np.asarray(self.path_m),
                                   [(lm.node, lm.points) for lm in self.landmarks],
                                   self.cfg.cov_scale(True), self._floor(),
                                   self.cfg.long_range_cfg, self.cfg.grid_cfg("ties"),
                                   self.step_covs, self.edges)
            for cl in ties:
                self.edges.append(Edge(cl.old, cl.new, cl.z, _sqrt_info(cl.cov), loop=True))
            self.long_range_ties = len(ties)
            if ties:
                self.optimise()
        if self.cfg.reweight_edges:  # variance_components.py
            x, self.edges, self.class_factors = reweighted_solve(
                np.array(self.poses), self.edges, edge_classes(self.edges),
                self.cfg.variance_cfg)
            self.poses = list(x)
        return np.array(self.poses)


def _in_frame(pose: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """A world-frame pose covariance seen in the frame of ``pose``."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rot = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    return rot @ cov @ rot.T


__all__ = ["Edge", "LaserMapper", "Landmark", "MappingConfig", "OdometryCalibration",
           "_sqrt_info", "solve_pose_graph"]
