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
    return out


if __name__ == "__main__":
    from compare import print_table

    print_table(rows())
