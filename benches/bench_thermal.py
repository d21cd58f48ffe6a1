"""Thermal network: simulation, calibration and the whole diagnosis, timed on synthetic runs.
There is no third-party reference for the diagnosis; the reference column for the simulation
is the project's scipy-expm integrator (synthetic.simulate_truth) on the same machine and run."""

from __future__ import annotations

from _timing import best_of

SIZES = ((20.0, 60.0), (20.0, 10.0))  # hours, sampling step in s


def rows(sizes=SIZES, repeat: int = 3) -> list[dict]:
    import thermerr_rs as tr
    from thermerr_rs import synthetic as syn
    from thermerr_rs.thermal import Machine, diagnose

    out = []
    for hours, dt in sizes:
        c = syn.make_case("vmc", "thermal_lag", 1, hours=(hours, hours * 0.6), dt=dt)
        run, hold = tr.Run.from_frame(c.train), tr.Run.from_frame(c.test)
        truth = Machine.from_toml(syn.to_toml(c.truth))
        n = len(run)
        ours = best_of(lambda: truth.simulate(run), repeat)
        ref = best_of(lambda: syn.simulate_truth(c.truth, c.train), 1)
        out.append(dict(task="simulate (5 nodes)", size=f"{n} steps", ours_s=ours, ref_s=ref, ratio=ref / ours, note="ref: scipy expm"))
        nominal = Machine.from_toml(c.nominal_toml())
        ours = best_of(lambda: diagnose(run, nominal, hold), 1)
        out.append(dict(task="diagnose (21 candidates)", size=f"{hours:.0f} h @ {dt:.0f} s", ours_s=ours, ref_s=float("nan"), ratio=float("nan"), note="target < 10 s at 1 min"))
    out.extend(jitter_rows(repeat))
    return out


def jitter_rows(repeat: int = 3) -> list[dict]:
    """A logger that jitters (±0.5 s on 60-s samples) against the same run on exact times: with
    one matrix exponential per distinct step this was 28x slower (185 s vs 6.7 s for diagnose);
    the times are now put on a 1/32-s grid. The ratio column is jittered / exact (1 is the aim)."""
    import numpy as np

    import thermerr_rs as tr
    from thermerr_rs import synthetic as syn
    from thermerr_rs.thermal import Machine, diagnose

    c = syn.make_case("vmc", "thermal_lag", 1, hours=(20.0, 12.0), dt=60.0)
    rng = np.random.default_rng(0)

    def jittered(frame):
        f = dict(frame)
        t = np.asarray(f["time_s"], dtype=float)
        f["time_s"] = t + rng.uniform(-0.5, 0.5, t.shape[0]).round(3)
        return tr.Run.from_frame(f)

    exact = (tr.Run.from_frame(c.train), tr.Run.from_frame(c.test))
    jit = (jittered(c.train), jittered(c.test))
    nominal = Machine.from_toml(c.nominal_toml())
    out = []
    for task, fn in (("calibrate, jittered 60 s", lambda r, h: nominal.calibrate(r)),
                     ("diagnose, jittered 60 s", lambda r, h: diagnose(r, nominal, h))):
        t_exact = best_of(lambda: fn(*exact), 1 if "diagnose" in task else repeat)
        t_jit = best_of(lambda: fn(*jit), 1 if "diagnose" in task else repeat)
        out.append(dict(task=task, size=f"{len(exact[0])} steps", ours_s=t_jit, ref_s=t_exact,
                        ratio=t_jit / t_exact, note="ref: same run on exact times; ratio jittered/exact"))
    return out


if __name__ == "__main__":
    from compare import print_table

    print_table(rows())
