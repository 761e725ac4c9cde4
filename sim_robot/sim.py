"""The simulation clock: sim time runs ``time_scale`` times faster than wall time."""

from __future__ import annotations

import time


class SimClock:
    def __init__(self, time_scale: float = 1.0) -> None:
        if time_scale <= 0:
            raise ValueError("time scale must be positive")
        self.time_scale = time_scale
        self._t0 = time.monotonic()

    def now(self) -> float:
        """Sim seconds since start."""
        return (time.monotonic() - self._t0) * self.time_scale

    def wall_until(self, t_sim: float) -> float:
        """Wall seconds until sim time ``t_sim`` (negative when past)."""
        return (t_sim - self.now()) / self.time_scale


class TruthLogger:
    """Writes ground truth as JSON lines for offline evaluation (never to the desk)."""

    def __init__(self, path: str, world, clock: SimClock, period_s: float = 0.5) -> None:
        import threading

        self.world = world
        self.clock = clock
        self.period_s = period_s
        self._f = open(path, "w", encoding="utf-8")  # noqa: SIM115 - closed in close()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="truth-log", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _run(self) -> None:
        import json

        from app.comm.protocol import now_us

        while not self._stop.wait(self.period_s):
            t = self.clock.now()
            w = self.world
            p = w.pose
            temp, hum = w.ambient(t)
            wd, ws = w.wind_at(t)
            rec = {"utc_us": now_us(), "sim_s": round(t, 3), "x_m": p.x, "y_m": p.y,
                   "theta_rad": p.theta, "v_mps": p.v, "omega_rps": p.omega,
                   "gas_lel_pct": w.gas_lel_pct(p.x, p.y, t), "temp_c": temp,
                   "humidity_pct": hum, "wind_dir_rad": wd, "wind_mps": ws,
                   "gauges": {g.id: g.value(t) for g in w.gauges},
                   "people": [[round(v, 2) for v in row[:2]] for row in w.people(t)]}
            self._f.write(json.dumps(rec) + "\n")
            self._f.flush()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self._f.close()
