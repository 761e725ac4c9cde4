"""The laser mapper's configuration (mapping.py's module docstring says what
each part does: the local step's matching and fusion, loop closure, the
pose graph, the final pass and the long-range ties)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from .icp import IcpConfig
from .long_range import LongRangeConfig
from .loop_closure import LoopConfig
from .odometry_noise import OdometryNoiseConfig
from .partial_overlap import PartialOverlapConfig
from .submap_match import SubmapConfig
from .variance_components import VarianceComponentConfig


@dataclass(frozen=True)
class MappingConfig:
    landmark_dist_m: float = 0.4  # a new landmark when no recent one is this near...
    landmark_angle_rad: float = math.radians(15)  # ...or turned this far from it
    local_landmarks: int = 5  # recent landmarks that make the local reference
    # dead-reckoning noise per step (odometry_noise.py): the calibration's
    # remaining uncertainty plus a random part whose level is learnt
    odometry_noise: OdometryNoiseConfig = field(default_factory=OdometryNoiseConfig)
    icp_window_xy_m: float = 0.5  # correlative search when ICP from the prediction fails
    icp_window_theta_rad: float = math.radians(12)
    icp_window_theta_per_rad: float = 0.15  # ...plus this fraction of the odometry turn
    # a turn this large between scans: the correlative search runs as well as
    # ICP from the prediction (a turn's odometry error can put ICP in a rival
    # minimum that still fits well), and the better fit is kept
    search_turn_rad: float = math.radians(15)
    match_gate_chi2: float = 16.0  # innovation test of a match against the prediction (3 dof)
    # a heading innovation m σ > k σ of (odometry + match): R × (m / k)² (Huber)
    match_heading_k: float = math.inf
    min_inlier_fraction: float = 0.45
    # a fit under that share is a partial overlap, fused when it holds enough
    # points and passes the innovation test (partial_overlap.py)
    partial: PartialOverlapConfig = field(default_factory=PartialOverlapConfig)
    # icp_cov_scale 8 was measured and not adopted: edmonton's 1 m RPE 4.1 -> 3.6 cm and the
    # freiburg variants alike or better (bench/localisation_bench.py method
    # full-cov8, 3 draws), but the station's mapping mode 95.9 -> 90.1 %
    # coverage (mapping_mode_bench.py --seed 0 --icp-cov-scale 8) and a drive
    # on odometry 8 % long (test_submap_match.py's) 6.7 -> 14.9 cm off. The
    # gain is the fused step leaning on odometry's translation (on edmonton's
    # raw-like odometry 2.8 cm rms per step, against 5.0 cm for the step the
    # match implies from the previous pose; the fixed model claims 7 cm per
    # axis), which carries odometry's scale error whole: the distance scale
    # is learnt only from matches stating <= 2 cm along the motion
    # (odometry_calibration.py), and that drive's state 3-6 cm (its scale
    # stays 1). Learning it from every match, weighted, with a weaker prior
    # mended that drive (6.8 cm with 8) but broke the station's map (77.5 %
    # coverage with 4, 92.0 % with 8). Measured once after this was decided,
    # on the held-out edmonton-harsh, 8 failed one draw of 3 (ATE 0.35 m; 4: 0.16).
    icp_cov_scale: float = 4.0  # the Hessian covariance is optimistic (scan correlation)
    # ...and blind to errors it cannot see (wrong pairings, the beams' own
    # discretisation; Censi 2007): every graph edge's σ is at least this
    edge_floor_xy_m: float = 0.03
    edge_floor_theta_rad: float = math.radians(0.5)
    loop_closure: bool = True
    loop_every_m: float = 1.5  # path between two loop closures
    loop_search_every_m: float = 2.0  # at most one correlative search per this much path
    loop: LoopConfig = field(default_factory=LoopConfig)
    solve_min_correction_m: float = 0.05
    # the online solve is spread over the steps: at most this many Gauss-Newton
    # iterations per scan (one in a step that verified loop closures), until
    # the largest change is below ``solve_tol``; finish() solves to the end
    solve_iterations_per_step: int = 3
    solve_tol: float = 1e-4
    calibrate_odometry: bool = True
    backend: str = "graph"  # "graph": pose graph; "ekf": seed 002's landmark EKF
    prune_sigma: float = 25.0  # a loop edge left this many σ off after a solve is dropped
    final_pass: bool = False  # finish() matches every landmark again (loop_closure.py)
    # the final pass, the ties and the reweighting run this many times, each
    # round from the poses the last one solved and replacing its edges (2 was
    # tried on edmonton-every2's failing draws: the map's error moved about,
    # the edges got no more accurate; docs/localisation.md)
    final_rounds: int = 1
    # ...and then against whole earlier regions of the map (long_range.py)
    long_range: bool = True
    long_range_cfg: LongRangeConfig = field(default_factory=LongRangeConfig)
    icp: IcpConfig = field(default_factory=IcpConfig)
    # the local and loop-closure references know which side each wall point
    # was seen from (icp.stacked_reference's ``faces``): a scan from the other
    # side of a thin wall is not pulled across its thickness
    faces: bool = False
    # scan-to-submap matching (submap_match.py): the ICP fit searched round
    # (± window) and refined on the local landmarks' smoothed grid
    submap: bool = True
    submap_window_xy_m: float = 0.15
    submap_window_theta_rad: float = math.radians(2)
    submap_covariance: bool = True  # the grid's covariance (Olson) instead of ICP's
    # the submap's own uncertainty added to the match's covariance
    # (match_covariance.py, 3.): "heading", each keyframe step's heading
    # variance with its lever arm; "full", the whole step covariance; "off"
    # (the default: fused, either made the logs' maps worse; the module's 3.)
    submap_spread: str = "off"
    # the ICP fit's and the grid fit's disagreement d adds k² d dᵀ to the
    # match's covariance (mapping.py's docstring); 0: off. 1.5 chosen on the
    # station's mapping mode (bench/mapping_mode_bench.py); on the logs, 3
    # draws (bench/localisation_bench.py --methods full): freiburg ATE 0.039
    # -> 0.040 m, RPE 1 m 3.0 -> 2.9 cm; edmonton ATE 0.154 [worst 0.186] ->
    # 0.146 [0.156] m, RPE 1 m 4.1 -> 3.9 cm / 0.36 -> 0.34°. Measured once
    # after the choice on the held-out variants: edmonton-harsh ATE 0.224
    # [0.362] -> 0.238 [0.387] m, RPE 1 m 0.37 -> 0.40°; edmonton-reversed
    # 0.218 [0.399] -> 0.169 [0.218] m, RPE 1 m 0.34 -> 0.31°
    match_disagreement_k: float = 1.5
    # where it goes: "fusion" (the default), into the match's covariance R, so
    # the step leans on odometry where the two fits part, and its graph edge
    # states that; "position", the same with the heading part of d left out;
    # "edge", the gain of the fit's own R and the edge's covariance what that
    # gain leaves with R + k² d dᵀ (Joseph form), unless d is outside the fit's
    # own spread (dᵀ R⁻¹ d > match_gate_chi2: one fit is in a rival minimum),
    # where it is "fusion". Why: on edmonton's draw 8 of 12 (ATE 0.264 m, the
    # others 0.13-0.19) the last 90 scans, a stretch no loop closes, end 0.6 m
    # off: the fused steps there are 4.3° off over 50 steps, all one way,
    # where with k = 0 they are 1.3° off. A heading disagreement hands the
    # step's heading to odometry, whose turn error left after the calibration
    # (0.6-0.8°/m learnt of the 0.94 drawn, as the same calibration fed the
    # reference's steps learns it: the draw's random turns) has one sign over
    # many steps. But the disagreement is also what stops a wrong grid fit:
    # edmonton-every2 draw 2's step 48, the grid fit 6.3° off and ICP 1.3°,
    # fused 2.3° off with "fusion", 6.3° with the gain of the fit alone.
    # Measured (bench/localisation_bench.py --methods full, full-xydis,
    # full-edgedis), ATE mean [worst]: edmonton, 12 draws, fusion 0.163
    # [0.264], position 0.160 [0.191], edge 0.158 [0.188] m, RPE 1 m 3.9, 3.8,
    # 4.1 cm; edmonton-every2, 8 draws, 0.172 [0.229], failures of 1.88 and
    # 2.06 m (position), 0.225 [0.488] (edge); freiburg harsh and every2-harsh,
    # 8 draws, all three alike (0.04-0.06 m). Neither is adopted.
    # "mixture" (the default; match_mixture.py): the two fits as two
    # hypotheses of one match, weighed as the PDAF weighs its measurements
    # (odometry only arbitrating), the match z_grid − β_icp d with
    # R + (k² − β_g β_i) d dᵀ: the former rule where one fit weighs all.
    # Measured with the long-range ties' covariance test (long_range.py),
    # bench/localisation_bench.py --part logs --methods full / full-fusion,
    # ATE mean [worst], RPE 10 m: edmonton draws 0-11 0.156 [0.206] /
    # 0.157 [0.249] m, 7.9 / 7.7 cm; draws 12-23 0.150 [0.190] / 0.165
    # [0.204]; edmonton-every2 draws 0-7 0.177 [0.209] / 0.159 [0.223] m,
    # 8.0 / 7.7 cm; draws 8-15 0.222 [0.357] / 0.209 [0.336] m (2 and 3
    # draws over 0.25 m; before both changes 4, worst 0.793); freiburg alike.
    # RPE 1 m alike; RPE 10 m 0.2-0.3 cm worse with the mixture. The station's
    # mapping mode keeps "fusion" (sim_robot/mapping_mode.py).
    match_disagreement: str = "mixture"
    submap_cfg: SubmapConfig = field(default_factory=SubmapConfig)
    # which submap grids know the way each wall faces (face_grid.py, with
    # ``face_bins`` orientation layers): "off"; "final", the final pass's;
    # "ties", the final pass's and the long-range ties'; "all", those and
    # the local step's and the loop closures' (figures: docs/localisation.md,
    # "A face-aware grid fit for thin walls")
    face_grid: str = "off"
    face_bins: int = 12
    # after the final pass and the ties, the step edges' and the loop edges'
    # covariances are rescaled by their variance components, estimated from
    # the graph's own residuals, and the graph solved again
    # (variance_components.py; docs/localisation.md has the figures)
    reweight_edges: bool = True
    variance_cfg: VarianceComponentConfig = field(default_factory=VarianceComponentConfig)

    def grid_cfg(self, where: str) -> SubmapConfig:
        """The submap grids' configuration at ``where`` ("local", "closure",
        "final" or "ties"): ``submap_cfg``, in orientation layers where
        ``face_grid`` says so."""
        on = {"off": (), "final": ("final",), "ties": ("final", "ties"),
              "all": ("local", "closure", "final", "ties")}[self.face_grid]
        return replace(self.submap_cfg, face_bins=self.face_bins) if where in on \
            else self.submap_cfg

    def cov_scale(self, submap: bool = False) -> float:
        """The factor on a match's covariance: ICP's (and Olson's grid
        covariance) count every beam as independent and are optimistic
        (``icp_cov_scale``); the submap's residual covariance
        (match_covariance.py) already counts correlated beams: 1."""
        return 1.0 if submap and self.submap_cfg.covariance == "residual" \
            else self.icp_cov_scale
