"""Model selection (issue 12 point 2): candidates scored on time-ordered splits of the training run
only, ranked by held-out RMS, the winner refitted; reproducible from the seed."""

from __future__ import annotations

import json

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.errors import ParameterError
from thermerr_rs.model_selection import RIDGE_PATH, Candidate, Entry, candidates, edge_latency, pick, select_model

SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]


def test_the_leaderboard_is_the_time_ordered_cv_of_each_candidate(example_run1):
    run = tr.read_run(example_run1)
    sel = select_model(run, "E_z", SENSORS, families=["mlr", "svr"], cv=4)
    assert len(sel.leaderboard) == len(RIDGE_PATH) + 9
    rms = [e.cv_rms for e in sel.leaderboard]
    assert rms == sorted(rms)
    # recompute the MLR entry by hand on the same splits
    x = run.input_matrix(SENSORS, "rise")
    y = run["E_z"]
    by_hand = []
    for train, test in tr.time_series_split(len(run), 4):
        assert train.max() < test.min()
        m = tr.MLR().fit(x[train], y[train])
        by_hand.append(np.sqrt(np.mean((y[test] - m.predict(x[test])) ** 2)))
    mlr = next(e for e in sel.leaderboard if e.candidate.family == "mlr" and not e.candidate.params)
    assert mlr.cv_rms == pytest.approx(float(np.mean(by_hand)), rel=1e-12)
    # the winner is refitted on the whole run with its settings
    best = sel.best.candidate
    assert type(sel.model).__name__.lower() == best.family
    assert sel.model.n_features_in_ == len(SENSORS)


def test_same_seed_same_board(example_run1):
    run = tr.read_run(example_run1)
    a = select_model(run, "E_z", SENSORS, families=["rbf"], cv=3, seed=4)
    b = select_model(run, "E_z", SENSORS, families=["rbf"], cv=3, seed=4)
    assert [e.cv_rms for e in a.leaderboard] == [e.cv_rms for e in b.leaderboard]


def test_history_doubles_the_candidates_and_is_refitted_with_the_winner(example_run1):
    cands = candidates(["mlr", "rbf", "svr"], [900.0])
    assert len(cands) == 2 * (len(RIDGE_PATH) + 9 + 9)
    # scored family by family, each without then with history: a budget that runs out cuts the
    # costly SVRs, not the MLRs with history
    assert [(c.family, c.history) for c in cands[:2 * len(RIDGE_PATH)]] == \
        [("mlr", None)] * len(RIDGE_PATH) + [("mlr", (900.0,))] * len(RIDGE_PATH)
    assert [c.family for c in cands[-18:]] == ["svr"] * 18
    run = tr.read_run(example_run1)
    sel = select_model(run, "E_z", SENSORS, families=["mlr"], history=[900.0, 3600.0], cv=3)
    best = sel.best.candidate
    assert (sel.model.input_history_ is not None) == (best.history is not None)


def test_the_winner_is_timed_as_the_edge_runs_it(example_run1):
    run = tr.read_run(example_run1)
    sel = select_model(run, "E_z", SENSORS, families=["mlr", "svr"], history=[900.0], cv=3)
    p50, p99 = sel.edge_latency_us
    assert 0.0 < p50 <= p99 and np.isfinite(p99)
    assert sel.to_dict()["edge_latency_us"] == {"p50": p50, "p99": p99}
    assert "winner on the edge" in sel.table()
    # every candidate timed the edge's way too (its last split's model on its inputs)
    assert all(np.isfinite(e.edge_us) and e.edge_us > 0 for e in sel.leaderboard)
    assert all("edge_us_per_sample" in row for row in sel.to_dict()["leaderboard"])
    # any run-fitted model can be timed (the figures are measured, not asserted: benches/ compares)
    assert all(np.isfinite(edge_latency(tr.SVR().fit_run(run, "E_z", SENSORS), run, samples=50)))
    with pytest.raises(tr.ParameterError, match="fit_run"):
        edge_latency(tr.MLR().fit(np.ones((5, 2)) * np.arange(5)[:, None], np.arange(5.0)), run)


def test_budget_and_bad_input(example_run1):
    run = tr.read_run(example_run1)
    sel = select_model(run, "E_z", SENSORS, families=["svr"], cv=3, budget_s=1e-9)
    assert len(sel.leaderboard) == 1 and len(sel.skipped) == 8
    with pytest.raises(tr.ParameterError, match="unknown families"):
        select_model(run, "E_z", SENSORS, families=["forest"])
    with pytest.raises(tr.ParameterError, match="budget_s"):
        select_model(run, "E_z", SENSORS, budget_s=0)


def test_a_swarm_tuned_svr_is_one_more_candidate_searched_on_the_same_splits(example_run1):
    run = tr.read_run(example_run1)
    sel = select_model(run, "E_z", SENSORS, families=["svr"], cv=3, tune="cso", tune_pop=6, tune_iters=3, seed=2)
    assert len(sel.leaderboard) == 9 + 1
    tuned = next(e for e in sel.leaderboard if e.candidate.tune)
    assert tuned.candidate.tune == ("cso", 6, 3) and "tuned=cso 6x3" in tuned.candidate.label()
    # its C and gamma are tune_svr's, in its default box, on the same time-ordered splits of the
    # same inputs
    x, y = run.input_matrix(SENSORS, "rise"), run["E_z"]
    splits = tr.time_series_split(len(run), 3)
    res = tr.tune_svr(x, y, cv=splits, pop=6, iters=3, seed=2, progress=False)
    assert (tuned.candidate.params["C"], tuned.candidate.params["gamma"]) == (res.C, res.gamma)
    # and it is scored like every other candidate: the mean RMS over the splits
    by_hand = [np.sqrt(np.mean((y[te] - tr.SVR(C=res.C, gamma=res.gamma).fit(x[tr_], y[tr_]).predict(x[te])) ** 2))
               for tr_, te in splits]
    assert tuned.cv_rms == pytest.approx(float(np.mean(by_hand)), rel=1e-12)
    assert sel.to_dict()["leaderboard"][sel.leaderboard.index(tuned)]["tuned"] == ["cso", 6, 3]
    with pytest.raises(tr.ParameterError, match="tune"):
        select_model(run, "E_z", SENSORS, tune="ga")


def test_cli_model_auto(example_run1, example_run2, tmp_path, capsys):
    from thermerr_rs.cli import main

    out = tmp_path / "auto.json"
    assert main(["fit", str(example_run1), "--axis", "E_z", "--model", "auto", "--sensors", ",".join(SENSORS),
                 "--cv", "3", "--test", str(example_run2), "--out", str(out), "--json", "--no-fallbacks"]) == 0
    report = json.loads(capsys.readouterr().out)
    board = report["selection"]["leaderboard"]
    # without --history, auto tries every candidate without and with AUTO_HISTORY (900 s, 1 h)
    win = board[report["selection"]["winner"]]
    assert len(board) == 2 * (len(RIDGE_PATH) + 9 + 9) and report["model"] == win["model"] and report["selection"]["rule"] == "1se"
    assert sum(e["history"] == [900.0, 3600.0] for e in board) == len(RIDGE_PATH) + 9 + 9
    assert json.loads(out.read_text())["kind"] == win["family"]
    # --history none: the candidates without
    assert main(["fit", str(example_run1), "--axis", "E_z", "--model", "auto", "--sensors", ",".join(SENSORS),
                 "--cv", "3", "--history", "none", "--out", str(out), "--json", "--no-fallbacks"]) == 0
    board = json.loads(capsys.readouterr().out)["selection"]["leaderboard"]
    assert len(board) == len(RIDGE_PATH) + 9 + 9 and all(e["history"] is None for e in board)
    # --select min: the lowest CV RMS
    assert main(["fit", str(example_run1), "--axis", "E_z", "--model", "auto", "--sensors", ",".join(SENSORS),
                 "--cv", "3", "--history", "none", "--select", "min", "--out", str(out), "--json",
                 "--no-fallbacks"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["selection"]["winner"] == 0 and report["model"] == report["selection"]["leaderboard"][0]["model"]


def test_cli_model_auto_with_tune(example_run1, tmp_path, capsys):
    from thermerr_rs.cli import main

    out = tmp_path / "auto.json"
    assert main(["fit", str(example_run1), "--axis", "E_z", "--model", "auto", "--sensors", ",".join(SENSORS),
                 "--cv", "3", "--tune", "pso", "--pop", "4", "--iters", "2", "--history", "none", "--out", str(out),
                 "--json", "--no-fallbacks"]) == 0
    board = json.loads(capsys.readouterr().out)["selection"]["leaderboard"]
    assert len(board) == len(RIDGE_PATH) + 9 + 9 + 1 and sum(e["tuned"] == ["pso", 4, 2] for e in board) == 1


def test_cli_model_auto_draws_a_bar_on_a_terminal(example_run1, tmp_path, capsys, monkeypatch):
    from thermerr_rs import cli

    monkeypatch.setattr(cli, "_progress_enabled", lambda args: True)  # as when stderr is a terminal
    out = tmp_path / "auto.json"
    assert cli.main(["fit", str(example_run1), "--axis", "E_z", "--model", "auto", "--sensors", ",".join(SENSORS),
                     "--cv", "3", "--out", str(out), "--no-fallbacks"]) == 0
    err = capsys.readouterr().err
    assert "model selection" in err and "candidate" in err  # the tqdm bar, not a line per candidate
    assert "candidate 1/42" not in err


def _entry(family: str, params: dict, cv: float, std: float) -> Entry:
    return Entry(Candidate(family, params, None), cv, std, 0.0, 0.0)


def test_the_one_standard_error_rule_takes_the_simplest_within_the_band() -> None:
    # sorted by CV RMS as select_model sorts; 5 splits: the standard error is std / sqrt(4)
    board = [
        _entry("svr", {"C": 100.0, "gamma": 0.01}, 2.70, 1.96),  # lowest; band up to 2.70 + 0.98 = 3.68
        _entry("mlr", {"alpha": 1.0}, 2.94, 1.88),
        _entry("mlr", {"alpha": 10.0}, 3.19, 1.40),
        _entry("rbf", {"n_centers": 10, "spread": 1.0}, 3.30, 1.00),
        _entry("mlr", {"alpha": 100.0}, 3.69, 1.30),  # just outside the band
    ]
    assert pick(board, 5, "min") == 0
    assert pick(board, 5, "1se") == 2  # MLR before the kernels, then the strongest ridge inside
    # one split has no spread: the lowest
    assert pick(board, 1, "1se") == 0
    # a band holding no MLR: the lowest CV RMS among the kernel models in it
    kernels = [_entry("svr", {}, 1.0, 0.2), _entry("rbf", {}, 1.05, 0.1), _entry("mlr", {}, 2.0, 0.1)]
    assert pick(kernels, 5, "1se") == 0
    # equal simplicity: the lower CV RMS
    ties = [_entry("mlr", {"alpha": 10.0}, 1.0, 0.4), _entry("mlr", {"alpha": 10.0}, 1.1, 0.1)]
    assert pick(ties, 5, "1se") == 0
    with pytest.raises(ParameterError, match="rule must be one of 1se, min"):
        pick(board, 5, "lowest")


def test_select_model_reports_its_rule_and_winner(example_run1):
    run = tr.read_run(example_run1)
    a = select_model(run, "E_z", SENSORS, families=["mlr", "svr"], cv=4)
    b = select_model(run, "E_z", SENSORS, families=["mlr", "svr"], cv=4, rule="min")
    assert [e.cv_rms for e in a.leaderboard] == [e.cv_rms for e in b.leaderboard]
    assert b.winner == 0 and b.best is b.leaderboard[0]
    assert a.winner == pick(a.leaderboard, a.n_splits, "1se") and a.best is a.leaderboard[a.winner]
    # the refitted model is the winner's
    assert type(a.model).__name__.lower() == a.best.candidate.family
    if a.best.candidate.family == "mlr":
        assert a.model.alpha == a.best.candidate.params.get("alpha", 0.0)
    d = a.to_dict()
    assert d["rule"] == "1se" and d["winner"] == a.winner
    assert "* " + a.best.candidate.label() in a.table()
    with pytest.raises(ParameterError, match="rule must be one of"):
        select_model(run, "E_z", SENSORS, families=["mlr"], rule="best")


def test_the_ridge_path_steps_at_most_half_a_decade() -> None:
    # the one-standard-error rule takes the strongest ridge inside its band, so its pick moves
    # with the path's steps: on the real run of docs/methods.md a decade grid jumped past the
    # alpha that every finer log path picked
    alphas = [a for a in RIDGE_PATH if a > 0]
    assert RIDGE_PATH[0] == 0.0 and alphas == sorted(alphas)
    # half decades as rounded numbers: 1, 3, 10, 30, ... (steps of 3 and 10/3 around sqrt(10))
    assert all(b / a <= 10.0 / 3.0 + 1e-9 for a, b in zip(alphas, alphas[1:]))
    assert alphas[0] <= 1.0 and alphas[-1] >= 1000.0
    mlr_alphas = [c.params.get("alpha", 0.0) for c in candidates(["mlr"], None)]
    assert mlr_alphas == list(RIDGE_PATH)
