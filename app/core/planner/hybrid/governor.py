"""The hybrid planner's safety governor: every command, kept within the
kinematic limits, is checked against the constant-velocity prediction of the
moving obstacles and a braking contingency (passive safety), and replaced by the
nearest safe reachable command when it fails (see the module docstring of
:mod:`app.core.planner.hybrid.planner`). Mixed into
:class:`~app.core.planner.hybrid.HybridPlanner`."""

from __future__ import annotations

import math

import numpy as np

from .config import WALL_SLACK_M
from .rollout import rollout_clearance, rollout_many, rollout_ramp


class SafetyGovernor:
    """Kinematic limits and the safety governor over (v, ω) commands."""

    def _limit(self, v, w, vc, wc, dt):
        k = self.cfg.kin
        v = min(max(v, k.v_min_mps, vc - k.accel_mps2 * dt), k.v_max_mps, vc + k.accel_mps2 * dt)
        w = min(
            max(w, -k.omega_max_rps, wc - k.alpha_rps2 * dt),
            k.omega_max_rps,
            wc + k.alpha_rps2 * dt,
        )
        return float(v), float(w)

    def _clearance(self, q, th, v, w, obs):
        ox, oy = self.grid.origin_xy
        return rollout_clearance(
            q[0],
            q[1],
            th,
            v,
            w,
            self.cfg.safety_horizon_s,
            0.1,
            self._dist,
            self.grid.resolution_m,
            ox,
            oy,
            obs,
            self.cfg.robot_radius_m,
            *self._grow,
        )

    def _govern(self, q, th, v, w, vc, wc, dt, obs, margin=None):
        """Keep (v, ω) if its rollout stays clear by the safety margin (or, with
        no moving obstacle in view and the robot already inside the margin,
        by half of what is left, so it can still move along a wall; and a
        robot the map has touching a wall already, by going no deeper).
        Otherwise take the safe reachable command nearest to (v, ω); when no
        reachable command is safe, the one whose rollout stays clearest."""
        margin = self.cfg.safety_margin_m if margin is None else margin
        d = self._clearance(q, th, v, w, obs)
        now = self._clearance(q, th, 0.0, 0.0, obs[:0])
        # The walls' floor. Half of what is left has no motion above it once
        # nothing is left (the body on or past the map's surface, which a
        # bumped robot or a pose estimate a few centimetres off reaches): the
        # robot then stood for good. There, any motion that goes no deeper.
        wall_ok = min(margin, 0.5 * now) if now > 0.0 else now - WALL_SLACK_M

        def safe(dd):
            return dd > margin or (len(obs) == 0 and dd > min(0.5 * min(now, margin), wall_ok))

        if safe(d) and (len(obs) == 0 or self._can_stop(q, th, vc, wc, v, w, obs) > margin):
            return v, w
        self.governor_count += 1
        # Search the whole velocity space within the kinematic limits: each
        # target (v, ω) is reached at the acceleration limits and then held;
        # the rollout checks every obstacle's predicted motion. Reversing is
        # a candidate whenever v_min < 0 (backing away from a squeeze). Safe:
        # clear of the moving obstacles by the margin, and of the walls by the
        # margin or half of what is left (a robot already close to a wall may
        # still move along it).
        k = self.cfg.kin
        vs = np.unique(np.concatenate([np.linspace(k.v_min_mps, k.v_max_mps, 7), [0.0, v]]))
        ws = np.unique(np.concatenate([np.linspace(-k.omega_max_rps, k.omega_max_rps, 9), [w]]))
        grid_v, grid_w = np.meshgrid(vs, ws, indexing="ij")
        # Turn in place to one of 12 headings, then drive off straight.
        phis = th + np.linspace(-math.pi, math.pi, 12, endpoint=False)[1:]
        errs = (phis - th + math.pi) % (2 * math.pi) - math.pi
        n_grid = grid_v.size
        cands = np.empty((n_grid + len(phis), 3))
        cands[:n_grid, 0] = grid_v.ravel()
        cands[:n_grid, 1] = grid_w.ravel()
        cands[:n_grid, 2] = np.nan
        cands[n_grid:, 0] = k.v_max_mps
        cands[n_grid:, 1] = np.copysign(k.omega_max_rps, errs)
        cands[n_grid:, 2] = phis
        out = self._rollouts(q, th, vc, wc, cands, obs, self._grow, math.inf)
        ds, dm, t_hit = out[:, 0], out[:, 1], out[:, 2]
        commit = self.cfg.commit_s
        if commit > 0.0 and len(obs):
            # The contingency of each candidate: held for commit_s, then
            # braked to rest; standing there must stay clear as well.
            brake = self._rollouts(q, th, vc, wc, cands, obs, self._grow, commit)
            can_stop = (brake[:, 1] > margin) & (brake[:, 0] > wall_ok)
        else:
            can_stop = np.ones(len(cands), bool)
        # Each candidate's first step, as in its rollout: a turn-then-go
        # stands and turns while more than 0.2 rad off its heading.
        tv, tw = cands[:, 0].copy(), cands[:, 1].copy()
        turn = np.zeros(len(cands), bool)
        turn[n_grid:] = True
        err_all = np.concatenate([np.zeros(n_grid), errs])
        far = turn & (np.abs(err_all) > 0.2)
        tv[far] = 0.0
        near = turn & ~far
        tw[near] = np.clip(2.0 * err_all[near], -k.omega_max_rps, k.omega_max_rps)
        lv = np.clip(
            tv, max(k.v_min_mps, vc - k.accel_mps2 * dt), min(k.v_max_mps, vc + k.accel_mps2 * dt)
        )
        lw = np.clip(
            tw,
            max(-k.omega_max_rps, wc - k.alpha_rps2 * dt),
            min(k.omega_max_rps, wc + k.alpha_rps2 * dt),
        )
        cost = np.where(
            turn,
            np.abs(lv - v) / k.v_max_mps + np.abs(lw - w) / k.omega_max_rps + 0.5,
            np.abs(cands[:, 0] - v) / k.v_max_mps + np.abs(cands[:, 1] - w) / k.omega_max_rps,
        )
        ok = (dm > margin) & (ds > wall_ok) & can_stop
        if not ok.any():  # nothing safe both ways: a motion it can at least stop from
            ok = can_stop & (ds > wall_ok)
        self.escape_found = bool(ok.any())
        if self.escape_found:
            i = int(np.flatnonzero(ok)[np.argmin(cost[ok])])
            return float(lv[i]), float(lw[i])
        self.cornered_count += 1
        # No motion the robot could stop clear from. An escape that never
        # meets an obstacle as predicted (a standing one's growing disc is a
        # precaution, left out here; a walker's uncertainty is kept) is
        # taken, the clearest one: a robot beside a standing person moves
        # away instead of freezing.
        if (self._grow[0] > 0.0 or self._grow[3] > 0.0) and len(obs):
            g = self._grow
            nominal = self._rollouts(q, th, vc, wc, cands, obs, (0.0, g[1], 0.0, g[3]), math.inf)
            t_hit = nominal[:, 2]
        clear = np.minimum(dm, ds - wall_ok)
        free = ~np.isfinite(t_hit) & (ds > wall_ok)
        if free.any():
            i = int(np.flatnonzero(free)[np.argmax(clear[free])])
            return float(lv[i]), float(lw[i])
        # Contact is coming whatever the robot does (passive safety): be at
        # rest, or as slow as possible, when it comes. Of the braking
        # contingencies, the one slowest at its contact, then the one whose
        # contact comes latest, then the clearest; without contingencies,
        # brake at the limit.
        self.estop_count += 1
        if not (commit > 0.0 and len(obs)):
            return self._limit(0.0, 0.0, vc, wc, dt)
        tb = np.minimum(brake[:, 2], self.cfg.safety_horizon_s)
        a = k.accel_mps2
        v_commit = vc + np.clip(tv - vc, -a * commit, a * commit)
        v_hit = np.where(
            tb <= commit,
            np.abs(vc + np.clip(tv - vc, -a * tb, a * tb)),
            np.maximum(np.abs(v_commit) - a * (tb - commit), 0.0),
        )
        cb = np.minimum(brake[:, 1], brake[:, 0] - wall_ok)
        i = int(np.lexsort((-np.arange(len(cands)), cb, tb, -np.round(v_hit, 2)))[-1])
        return float(lv[i]), float(lw[i])

    def _rollouts(self, q, th, vc, wc, cands, obs, grow, stop_after) -> np.ndarray:
        """rollout_many for the candidates from the robot's state, with the
        disc growth ``grow`` (as self._grow) and the contingency stop time."""
        k = self.cfg.kin
        ox, oy = self.grid.origin_xy
        return rollout_many(
            q[0],
            q[1],
            th,
            vc,
            wc,
            cands,
            k.accel_mps2,
            k.alpha_rps2,
            self.cfg.safety_horizon_s,
            0.1,
            self._dist,
            self.grid.resolution_m,
            ox,
            oy,
            obs,
            self.cfg.robot_radius_m,
            *grow,
            stop_after,
        )

    def _can_stop(self, q, th, vc, wc, v, w, obs) -> float:
        """Clearance to the moving obstacles of the contingency for (v, ω):
        held for commit_s, then braked to rest and standing (+inf if off)."""
        if self.cfg.commit_s <= 0.0:
            return math.inf
        k = self.cfg.kin
        ox, oy = self.grid.origin_xy
        _, dm, _ = rollout_ramp(
            q[0],
            q[1],
            th,
            vc,
            wc,
            v,
            w,
            k.accel_mps2,
            k.alpha_rps2,
            self.cfg.safety_horizon_s,
            0.1,
            self._dist,
            self.grid.resolution_m,
            ox,
            oy,
            obs,
            self.cfg.robot_radius_m,
            np.nan,
            *self._grow,
            self.cfg.commit_s,
        )
        return dm

    def govern(self, pose_xytheta, velocity, v, w, obstacles=(), dt: float = 0.1):
        """A command made elsewhere (a recovery manoeuvre), within the
        kinematic limits and through the safety governor: (v_mps, omega_rps)."""
        q = np.array([float(pose_xytheta[0]), float(pose_xytheta[1])])
        th = float(pose_xytheta[2])
        vc, wc = (float(velocity), 0.0) if np.ndim(velocity) == 0 else map(float, velocity)
        obs = np.asarray(list(obstacles), dtype=np.float64).reshape(-1, 5)
        v, w = self._limit(v, w, vc, wc, dt)
        return self._govern(q, th, v, w, vc, wc, dt, obs)
