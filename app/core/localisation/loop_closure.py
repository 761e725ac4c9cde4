"""Loop closure: candidates over a search window, verification, consistency.

When the robot comes back to a place it has mapped, the scan is matched
against an old landmark's neighbourhood and the match becomes a pose-graph
edge. A false closure bends the whole map, so each one passes three tests:

1. **Candidates.** Old landmarks (more than ``min_separation_m`` of path
   ago) within a search radius of the estimate, the radius growing with the
   drift the estimate may have gathered relative to that landmark: the path
   between them along the graph (``graph_path_m``: the chain of scans, or a
   shortcut through one accepted closure, whichever is shorter). Each
   is ranked by *view overlap*: the fraction of the current scan's points,
   placed at the estimate, within ``overlap_tolerance_m`` of the landmark's
   points (a coarse test: a 180° scan facing away from the old one sees
   little of it, whatever the distance). The best ``candidates`` distinct
   places are verified.
2. **Verification** (``matcher``: "icp", the default, "submap", or
   "both": ICP first, and the submap where ICP grades the place neither
   strong nor weak, at most ``submap_per_step`` per scan). "submap"
   (``verify_submap``): the candidate and its neighbouring keyframes rendered
   as one smoothed likelihood grid (submap_match.py), Olson's correlative
   search (ICRA 2009, §III) over the estimate ± a window at least
   ``submap_window_*`` wide (±1 m / ±10°) and as wide as the drift may be,
   Hess et al.'s least-squares fit on the grid (ICRA 2016, §IV.C), and
   Olson's covariance from the likelihood round the optimum; "icp"
   (``verify``): ICP from the estimate, and when that does not fit tightly
   a correlative search (icp.correlative_search) over the drift window, then
   ICP from its best pose. Either result is *strong* (most points on old
   walls, a small residual, a well-conditioned covariance: no corridor
   ambiguity) or *weak* (a partial overlap that fits well where it
   overlaps) or rejected. ICP's covariance is blind to a direction that
   only a few points hold (a wall's axis held by a post or a person):
   ``free_directions`` (a degeneracy test after Zhang, Kaess & Singh, ICRA
   2016) leaves such a direction free in the closure's edge.
3. **Consistency.** A strong closure is accepted at once. A weak one waits
   until another closure agrees with it: two closures a (old node i_a to new
   node j_a, measured z_a) and b close a cycle with the chains between their
   old nodes and between their new nodes, and

       e = (x_ja ⊖ x_jb) ⊖ ((x_ia ⊕ z_a) ⊖ (x_ib ⊕ z_b))            (LC-1)

   must be near the identity: |e_xy| ≤ t₀ + t₁ L, |e_θ| ≤ r₀ + r₁ L, L the
   path along the two chains (pairwise consistency, as in Olson's
   single-cluster graph partitioning, 2009, and Latif et al.'s RRR, 2013,
   reduced to pairs). A weak closure must also agree, by the same bounds,
   with the graph's current estimate of its two poses (``agrees_with_graph``:
   the cycle through the graph path, L the path between them), so that a
   partner far along a long cycle cannot vouch for a match that the graph
   nearby refutes. Closures that pass still meet a robust kernel in
   the pose graph (pose_graph.py).

A final pass (``final_pass``), once the whole log is mapped: with the
solved poses, which after the online closures are far better than the
estimates were when each scan came in, every landmark is matched again (no
search) against the old places it overlaps, and a match becomes an
edge when it is strong or weak (step 2) *and* moves the scan by no more than
``final_max_shift_m`` / ``final_max_turn_rad`` from the solution (a gate
against the graph itself: a match far from a consistent map is a rival
minimum, not a correction). This adds the many short "loops" between scans a
few metres apart that see the same walls, which hold the heading along open
stretches where no real loop closes. The grid fit is first searched (Olson's
correlative search, submap_match.search) over the very window the gate
accepts, ± ``final_window_xy_m`` / ``final_window_theta_rad`` (0.3 m, 2°),
then refined: refined from the solved pose alone, a pose more than the
refinement's reach (its 2.5 σ = 20 cm cap) off stayed off, and the edge
repeated the solution's error (edmonton-every2: final-pass edges 20–27 cm
off, bench/loop_edge_errors.py). The match (``final_matcher``) is by
default the local step's own: the grid fit on a submap of the place's
keyframes (submap_match.py) with Olson's covariance, graded as ICP's. The
final pass's edges are many and short, so their stated uncertainty decides
how far they bend the chain locally. ICP's (its Hessian's, × 4, plus the
graph's floor) claimed ≈ 3.5 cm where its edges were 1.4–1.5 σ off against
edmonton's reference (keyframes at their reference poses; freiburg 1.1 σ),
and the pass made edmonton's 1 m relative pose error worse (3.8 cm in the
online map, 4.4 cm after the pass, 3 odometry draws) while it mended the
large loops; the grid fit's edges are no more accurate (heading slightly
less) but state ≈ 6 cm, 0.7–0.9 σ off, and with them it is 4.1 cm
(bench/localisation_bench.py). A place's submap is shared by the
neighbouring landmarks that match it (a few kept).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .icp import (
    IcpConfig,
    IcpResult,
    Reference,
    correlative_search,
    icp,
    pair_information,
    stacked_reference,
)
from .se2 import compose, relative, transform_points, wrap
from .submap_match import Submap, SubmapConfig, match_submap


@dataclass(frozen=True)
class LoopConfig:
    min_separation_m: float = 6.0  # path between the old landmark and now
    radius_m: float = 4.0  # search radius round the estimate...
    radius_growth: float = 0.05  # ...plus this per metre of graph path to the landmark
    radius_max_m: float = 10.0
    candidates: int = 3  # places verified per scan
    overlap_tolerance_m: float = 1.0
    min_overlap: float = 0.35
    overlap_points: int = 60
    neighbours: int = 2  # landmarks either side of a candidate in its reference
    window_xy_m: float = 0.6  # correlative window: this...
    window_xy_per_m: float = 0.02  # ...plus this per metre of graph path
    window_xy_max_m: float = 2.0
    window_theta_rad: float = math.radians(10)
    window_theta_per_m: float = math.radians(0.2)
    window_theta_max_rad: float = math.radians(30)
    strong_inliers: float = 0.7
    strong_rmse_m: float = 0.045
    strong_sigma_m: float = 0.05
    weak_inliers: float = 0.4
    weak_rmse_m: float = 0.06
    weak_sigma_m: float = 0.08
    # a direction along which the match's inlier pairs hold fewer than this many
    # points' worth of constraint (``free_directions``) is left free in the closure
    # edge: its σ there is ``free_sigma_m``
    degenerate_points: float = 10.0
    free_sigma_m: float = 1.0
    cycle_trans_m: float = 0.25  # t₀ of LC-1
    cycle_trans_per_m: float = 0.01  # t₁
    cycle_rot_rad: float = math.radians(1.5)  # r₀
    cycle_rot_per_m: float = math.radians(0.05)  # r₁
    cycle_max_path_m: float = 40.0  # longer chains drift too much to vouch
    pending_m: float = 20.0  # a weak closure waits this much path for a partner
    final_radius_m: float = 10.0  # final pass: places this near are matched again...
    final_candidates: int = 4  # ...the best this many by view overlap
    final_max_shift_m: float = 0.3
    final_max_turn_rad: float = math.radians(2)
    # the final pass's grid fit searched first (Olson) within ± this of the
    # solved pose, the gate's own window (0: refined from the solved pose alone)
    final_window_xy_m: float = 0.3
    final_window_theta_rad: float = math.radians(2)
    # "submap": verification against a grid of the candidate's keyframes
    # (``verify_submap``); "icp": ICP, then icp.correlative_search (``verify``);
    # "both": ICP first, the submap where ICP grades the place neither way
    matcher: str = "icp"
    final_matcher: str = "submap"  # the final pass: "submap" (the grid fit) or "icp"
    # the final pass's edges leave free the directions their inlier pairs
    # hardly hold (``free_directions``, as the online closures do); off on the
    # logs (their figures were made without it), on in the station's mapping
    # mode (sim_robot/mapping_mode.py): there the grid fit's Olson covariance,
    # taken over ± ``submap_cov_steps`` fine steps, stated 8-16 cm along a
    # road's axis however free the road left it, and the pass's many edges
    # held the solution's own error along the road (up to 30 cm off,
    # docs/localisation.md)
    final_free_directions: bool = False
    submap_window_xy_m: float = 1.0  # the submap search's window: at least this...
    submap_window_theta_rad: float = math.radians(10)  # ...or the drift window
    submap_cov_steps: int = 4  # Olson's covariance over ± this many fine steps
    submap_per_step: int = 1  # places verified against a submap per scan (CPU)
    submap_cov_scale: float = 1.0  # Olson's covariance times this (graded as it is)


@dataclass
class Closure:
    old: int  # node of the old landmark
    new: int  # the current node
    z: np.ndarray  # pose of ``new`` seen from ``old``
    cov: np.ndarray  # 3×3, in ``old``'s frame
    strong: bool
    inliers: float


def graph_path_m(path_m: np.ndarray, k: int, nodes: np.ndarray,
                 closures: list[tuple[int, int]]) -> np.ndarray:
    """Path (metres) from each of ``nodes`` to node k through the graph: along
    the chain, |s_k − s_n|, or through one closure (a, b), |s_n − s_a| +
    |s_k − s_b| (either way round), whichever is shorter (s: path length at a
    node). The drift between two poses grows with this path, not with the
    time since the last closure anywhere."""
    s_n = path_m[nodes]
    best = np.abs(path_m[k] - s_n)
    for a, b in closures:
        via = np.minimum(np.abs(s_n - path_m[a]) + abs(path_m[k] - path_m[b]),
                         np.abs(s_n - path_m[b]) + abs(path_m[k] - path_m[a]))
        best = np.minimum(best, via)
    return best


def drift_window(cfg: LoopConfig, drift_m: float) -> tuple[float, float, float]:
    """(search radius, correlative xy window, θ window) for a landmark
    ``drift_m`` of graph path away."""
    return (min(cfg.radius_m + cfg.radius_growth * drift_m, cfg.radius_max_m),
            min(cfg.window_xy_m + cfg.window_xy_per_m * drift_m, cfg.window_xy_max_m),
            min(cfg.window_theta_rad + cfg.window_theta_per_m * drift_m,
                cfg.window_theta_max_rad))


class ViewOverlap:
    """Per-landmark k-d trees (built once, in the landmark's sensor frame) for
    the coarse view-overlap test of step 1."""

    def __init__(self) -> None:
        self._trees: dict[int, cKDTree] = {}

    def fraction(self, node: int, lm_points: np.ndarray, lm_pose: np.ndarray,
                 world_pts: np.ndarray, tol_m: float) -> float:
        if len(lm_points) == 0 or len(world_pts) == 0:
            return 0.0
        tree = self._trees.get(node)
        if tree is None:
            tree = self._trees[node] = cKDTree(lm_points)
        local = transform_points(relative(lm_pose, np.zeros(3)), world_pts)
        d, _ = tree.query(local, distance_upper_bound=tol_m)
        return float(np.mean(np.isfinite(d)))


def rank_candidates(here: np.ndarray, points: np.ndarray, olds, radius_m: np.ndarray | None,
                    overlap: ViewOverlap, cfg: LoopConfig,
                    near: np.ndarray | None = None) -> list[int]:
    """Indices into ``olds`` (node, pose, points) of the places to verify:
    within their ``radius_m``, overlap ≥ ``min_overlap``, best first, at most
    ``candidates``, no two within ``neighbours`` landmarks of each other.
    ``near``: the indices within their radius, when the caller has found
    them (then only those entries of ``olds`` are read; it may be a dict)."""
    if not olds or len(points) == 0:
        return []
    sub = points[np.linspace(0, len(points) - 1, min(cfg.overlap_points, len(points)))
                 .astype(int)]
    world = transform_points(here, sub)
    scored = []
    for n in (range(len(olds)) if near is None else near):
        node, pose, pts = olds[n]
        if near is None and math.hypot(pose[0] - here[0], pose[1] - here[1]) > radius_m[n]:
            continue
        f = overlap.fraction(node, pts, pose, world, cfg.overlap_tolerance_m)
        if f >= cfg.min_overlap:
            scored.append((f, int(n)))
    scored.sort(reverse=True)
    chosen: list[int] = []
    for _, n in scored:
        if all(abs(n - m) > cfg.neighbours for m in chosen):
            chosen.append(n)
        if len(chosen) == cfg.candidates:
            break
    return chosen


def grade(r: IcpResult, cfg: LoopConfig) -> str | None:
    """'strong', 'weak' or None (module docstring, step 2)."""
    if not r.converged or not math.isfinite(r.rmse_m):
        return None
    sig = math.sqrt(max(float(np.linalg.eigvalsh(r.covariance[:2, :2]).max()), 0.0))
    if r.inlier_fraction >= cfg.strong_inliers and r.rmse_m <= cfg.strong_rmse_m \
            and sig <= cfg.strong_sigma_m:
        return "strong"
    if r.inlier_fraction >= cfg.weak_inliers and r.rmse_m <= cfg.weak_rmse_m \
            and sig <= cfg.weak_sigma_m:
        return "weak"
    return None


def verify(points: np.ndarray, ref_points: np.ndarray | Reference, here: np.ndarray,
           window_xy_m: float, window_theta_rad: float, icp_cfg: IcpConfig, cfg: LoopConfig,
           may_search: bool) -> tuple[IcpResult, str | None, bool]:
    """Step 2: (match, grade, whether the correlative search ran). The place:
    points, or a reference (icp.stacked_reference: several scans, each with
    its own normals)."""
    ref = ref_points if isinstance(ref_points, Reference) else Reference(
        ref_points, icp_cfg.normal_neighbours, bucket_m=icp_cfg.bucket_m)
    ref_points = ref.points
    r = icp(points, ref, here, icp_cfg)
    g = grade(r, cfg)
    searched = False
    if g != "strong" and may_search and min(len(ref_points), len(points)) >= icp_cfg.min_points:
        seed, _ = correlative_search(points, ref.likelihood_field(), here, window_xy_m,
                                     window_theta_rad)
        r2 = icp(points, ref, seed, icp_cfg)
        g2 = grade(r2, cfg)
        searched = True
        rank = {"strong": 2, "weak": 1, None: 0}
        if rank[g2] > rank[g] or (rank[g2] == rank[g]
                                  and r2.inlier_fraction > r.inlier_fraction):
            r, g = r2, g2
    if g is not None:
        r.covariance = r.covariance.copy()
        r.covariance[:2, :2] += free_directions(points, ref, r.pose, icp_cfg, cfg)
    return r, g, searched


def free_directions(points: np.ndarray, ref: Reference, pose: np.ndarray, icp_cfg: IcpConfig,
                    cfg: LoopConfig) -> np.ndarray:
    """Step 2's degeneracy test (after Zhang, Kaess & Singh, "On degeneracy of
    optimization-based state estimation problems", ICRA 2016, §IV: the
    eigenvalues of the fit's approximate Hessian tell the directions the
    measurements do not constrain, and a solution keeps nothing along them).
    ICP's covariance (ICP-3) scales the Hessian's inverse by the fit's
    residual σ̂, a centimetre on a clean wall, so a corridor held along its
    axis by a few points (a post, a person, the edge of a shadow) claims the
    same 3 cm as a corner: along the wall the closure then says where the
    search or the drifted estimate put it, and a wrong pairing of those few
    points moves it by their size. The translation block of the inlier pairs'
    information, Σ n nᵀ (icp.pair_information, in points), is split into its
    eigenvectors; along one that fewer than ``degenerate_points`` points hold,
    the returned 2×2 (world frame, to add to the match's covariance) has a σ
    of ``free_sigma_m``: the edge constrains the pose across the wall and
    its heading, and leaves the position along it to the rest of the graph."""
    w, v = np.linalg.eigh(pair_information(points, ref, pose, icp_cfg))
    free = np.zeros((2, 2))
    for lam, vec in zip(w, v.T, strict=True):
        if lam < cfg.degenerate_points:
            free += cfg.free_sigma_m ** 2 * np.outer(vec, vec)
    return free


def verify_submap(points: np.ndarray, sub: Submap, here: np.ndarray, window_xy_m: float,
                  window_theta_rad: float, cfg: LoopConfig) -> tuple[IcpResult, str | None]:
    """Step 2 against a submap (submap_match.py): the candidate's keyframes
    rendered as one likelihood grid, Olson's correlative search over
    here ± the window (at least ``submap_window_*``: the drift since the
    candidate), Hess et al.'s least-squares refinement on the grid, and
    Olson's covariance from the likelihood round the optimum (over
    ±``submap_cov_steps`` fine steps, wide enough to see a corridor's
    spread); graded as an ICP fit is (``grade``): the share of points on
    the grid's walls, their RMS distance, the covariance's largest σ."""
    r = match_submap(points, sub, here, max(window_xy_m, cfg.submap_window_xy_m),
                     max(window_theta_rad, cfg.submap_window_theta_rad), cfg.submap_cov_steps)
    g = grade(r, cfg)
    r.covariance = r.covariance * cfg.submap_cov_scale
    return r, g


def cycle_error(a: Closure, b: Closure, poses) -> np.ndarray:
    """LC-1: the pose error round the cycle closed by closures a and b."""
    by_closures = relative(compose(poses[a.old], a.z), compose(poses[b.old], b.z))
    by_chain = relative(poses[a.new], poses[b.new])
    e = relative(by_chain, by_closures)
    e[2] = float(wrap(e[2]))
    return e


def consistent(a: Closure, b: Closure, poses, path_m, cfg: LoopConfig) -> bool:
    """Module docstring, step 3: a and b agree round their cycle."""
    chain = abs(path_m[a.new] - path_m[b.new]) + abs(path_m[a.old] - path_m[b.old])
    if chain > cfg.cycle_max_path_m:
        return False
    e = cycle_error(a, b, poses)
    return (math.hypot(e[0], e[1]) <= cfg.cycle_trans_m + cfg.cycle_trans_per_m * chain
            and abs(e[2]) <= cfg.cycle_rot_rad + cfg.cycle_rot_per_m * chain)


def agrees_with_graph(cl: Closure, poses, drift_m: float, cfg: LoopConfig) -> bool:
    """Step 3 for a weak closure: LC-1's bounds on the cycle the closure
    closes with the graph itself, its current estimate of the two poses,
    whose drift grows with the graph path ``drift_m`` between them
    (``graph_path_m``). A partner closure that agrees round a long cycle (up
    to ``cycle_max_path_m``) vouches for little: t₀ + t₁ L is 0.4 m there,
    and a match paired across a thin wall or a post is off by about that
    much; the graph, already bent by the closures accepted so far, is the
    shortest cycle there is. Directions the closure leaves free
    (``free_directions``) are not tested."""
    est = relative(poses[cl.old], poses[cl.new])
    nu = cl.z - est
    nu[2] = float(wrap(nu[2]))
    w, v = np.linalg.eigh(cl.cov[:2, :2])
    held = v[:, w < cfg.free_sigma_m ** 2 / 4]  # the constrained directions
    across = float(np.linalg.norm(held.T @ nu[:2]))
    return (across <= cfg.cycle_trans_m + cfg.cycle_trans_per_m * drift_m
            and abs(nu[2]) <= cfg.cycle_rot_rad + cfg.cycle_rot_per_m * drift_m)


def final_pass(poses: np.ndarray, path_m: np.ndarray,
               landmarks: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]],
               done: set[tuple[int, int]], icp_cfg: IcpConfig, cfg: LoopConfig,
               overlap: ViewOverlap, cov_scale: float,
               floor: np.ndarray | None = None,
               submap_cfg: SubmapConfig | None = None,
               faces: bool = False) -> list[Closure]:
    """The final pass of the module docstring. ``landmarks``: (node, points,
    normals, planar) in order (icp.scan_normals); ``done``: (old, new) pairs
    that already have an edge. With ``matcher`` "submap" each match is the
    least-squares refinement on the place's grid (no search: the solved
    poses are the guess) with Olson's covariance. ``faces``: the places'
    ICP references know which side each wall point was seen from
    (icp.stacked_reference), as the online closures' do. With
    ``cfg.final_free_directions`` a direction the match's inlier pairs
    hardly hold is left free in its edge (``free_directions``)."""
    out: list[Closure] = []
    nodes = np.array([lm[0] for lm in landmarks])
    grids: dict[tuple, Submap] = {}  # the places' submaps: neighbouring scans share them
    refs: dict[tuple, Reference] = {}  # ...and their ICP references
    for j, pts_j, _, _ in landmarks:
        older = np.flatnonzero(path_m[j] - path_m[nodes] > cfg.min_separation_m)
        if len(older) == 0:
            continue
        # the places within reach, found at once (the older landmarks are most of the
        # log: a loop over all of them per scan grew with the square of its length)
        gap = poses[nodes[older], :2] - poses[j, :2]
        near = np.flatnonzero(np.hypot(gap[:, 0], gap[:, 1]) <= cfg.final_radius_m)
        olds = {int(n): (int(nodes[older[n]]), poses[nodes[older[n]]], landmarks[older[n]][1])
                for n in near}
        picked = rank_candidates(poses[j], pts_j, olds, None, overlap,
                                 LoopConfig(candidates=cfg.final_candidates,
                                            min_overlap=cfg.min_overlap,
                                            overlap_tolerance_m=cfg.overlap_tolerance_m,
                                            neighbours=cfg.neighbours), near=near)
        for n in picked:
            old = olds[n][0]
            if (old, j) in done:
                continue
            group = older[max(0, n - cfg.neighbours):n + cfg.neighbours + 1]
            key = tuple(int(a) for a in group)
            ref = None
            if cfg.final_matcher != "submap" or cfg.final_free_directions:
                if key not in refs:
                    if len(refs) >= 16:  # bounded: the oldest place is dropped
                        del refs[next(iter(refs))]
                    refs[key] = stacked_reference(
                        [(poses[nodes[a]], *landmarks[a][1:]) for a in group],
                        icp_cfg.normal_neighbours, icp_cfg.bucket_m, faces)
                ref = refs[key]
            if cfg.final_matcher == "submap":
                if key not in grids:
                    if len(grids) >= 16:  # bounded: the oldest place is dropped
                        del grids[next(iter(grids))]
                    grids[key] = Submap([(poses[nodes[a]], landmarks[a][1]) for a in group],
                                        submap_cfg or SubmapConfig())
                sub = grids[key]
                r = match_submap(pts_j, sub, poses[j], cfg.final_window_xy_m,
                                 cfg.final_window_theta_rad, cfg.submap_cov_steps)
            else:
                r = icp(pts_j, ref, poses[j], icp_cfg)
            if grade(r, cfg) is None:
                continue
            move = relative(poses[j], r.pose)
            if math.hypot(move[0], move[1]) > cfg.final_max_shift_m or \
                    abs(move[2]) > cfg.final_max_turn_rad:
                continue
            rc = r.covariance * cov_scale
            if cfg.final_free_directions:
                rc = rc.copy()
                rc[:2, :2] += free_directions(pts_j, ref, r.pose, icp_cfg, cfg)
            c, sn = math.cos(poses[old][2]), math.sin(poses[old][2])
            rot = np.array([[c, sn, 0], [-sn, c, 0], [0, 0, 1]])
            cov = rot @ rc @ rot.T + (
                np.diag([1e-4, 1e-4, 1e-5]) if floor is None else floor)
            out.append(Closure(old, j, relative(poses[old], r.pose), cov,
                               grade(r, cfg) == "strong", r.inlier_fraction))
    return out
