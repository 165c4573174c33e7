"""xabsl tournament: plan, determinism across pool sizes, failures, git versions, report, Ctrl+C."""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import orjson
import pytest

from xabsl_studio.engine.cli import UsageError
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, load_team
from xabsl_studio.examples.soccer.tournament import cli, match, report, runners, versions

REPO = Path(__file__).resolve().parents[2]


def run_cli(*argv: str) -> int:
    parser = argparse.ArgumentParser(prog="xabsl")
    cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["tournament", *argv])
    return int(args.func(args))


def test_the_plan_plays_every_seed_both_ways_round():
    specs = match.plan(5, 7, 60.0)
    assert [(s.seed, s.home_blue) for s in specs] == [(7, True), (7, False), (8, True), (8, False), (9, True)]
    assert all(s.half_duration_s == 30.0 for s in specs)


def test_wilson_interval_matches_the_textbook_values():
    low, high = report.wilson(8, 10)
    assert low == pytest.approx(0.4902, abs=1e-4) and high == pytest.approx(0.9433, abs=1e-4)
    assert report.wilson(0, 10) == (0.0, pytest.approx(0.2775, abs=1e-4))
    assert report.wilson(10, 10) == (pytest.approx(0.7225, abs=1e-4), pytest.approx(1.0))
    assert report.wilson(0, 0) == (0.0, 1.0)


def test_colour_swap_maps_the_teams_back_to_the_versions():
    home, away = load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY)
    blue, red = (match.play(spec, home, away) for spec in match.plan(2, 3, 16.0))
    assert blue["ok"] and red["ok"]
    # HOME is the example team in both matches, whatever its colour: its options are its own.
    for result in (blue, red):
        assert "play_soccer" in result["activations"]["home"] and "chase_play" in result["activations"]["away"]
        assert "chase_play" not in result["activations"]["home"]
        assert all(key.split("/")[0] in result["activations"]["home"] for key in result["states"]["home"])
    assert blue["trace_hash"] != red["trace_hash"]


def test_one_and_two_jobs_give_identical_results(tmp_path, capsys):
    outputs = []
    for jobs in ("1", "2"):
        code = run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "3", "--duration", "12", "-j", jobs, "--json")
        assert code == 0
        outputs.append(orjson.loads(capsys.readouterr().out))
    one, two = outputs
    assert one["played"] == two["played"] == 3
    assert one["throughput"]["jobs"] == 1 and two["throughput"]["jobs"] == 2
    del one["throughput"], two["throughput"]
    assert one == two
    assert [m["seed"] for m in one["matches"]] == [1, 1, 2]
    assert [m["home_colour"] for m in one["matches"]] == ["blue", "red", "blue"]


def test_a_failing_match_is_reported_with_its_seed(capsys):
    home, away = load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY)
    good = match.plan(1, 5, 8.0)[0]
    bad = match.MatchSpec(1, 6, False, 4.0, players=0)  # no robots: the world refuses to build
    results: list[dict] = []
    runners.run_local([good, bad], (home, away), 2, results.append)
    by_index = {r["index"]: r for r in results}
    assert by_index[0]["ok"]
    assert not by_index[1]["ok"] and by_index[1]["seed"] == 6 and "Error" in by_index[1]["error"]
    summary = report.summarize(results, home="a", away="b", planned=2, wall_seconds=1.0, jobs=2, backend="local pool")
    assert summary["played"] == 1 and summary["failed"][0]["seed"] == 6
    assert [m["index"] for m in summary["matches"]] == [0, 1] and "error" in summary["matches"][1]


def test_a_match_over_its_timeout_fails_and_the_exit_status_says_so(capsys):
    code = run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "1", "--duration", "60", "--timeout", "0.01", "--json")
    summary = orjson.loads(capsys.readouterr().out)
    assert code == 1
    assert summary["played"] == 0
    assert summary["failed"][0]["seed"] == 1 and "MatchTimeout" in summary["failed"][0]["error"]


def _git(cwd: Path, *args: str) -> None:
    subprocess.run(
        ["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=cwd, check=True, capture_output=True
    )


def test_git_revision_against_the_working_tree(tmp_path, capsys):
    repo = tmp_path / "repo"
    shutil.copytree(DEFAULT_HOME, repo / "team")
    _git(repo, "init", "-q")
    _git(repo, "add", ".")
    _git(repo, "commit", "-qm", "first")
    # The working tree's striker never shoots: its shoot_at_goal state must run less.
    striker = repo / "team" / "options" / "striker.xabsl"
    text = striker.read_text()
    changed = text.replace("goto shoot;", "goto dribble;")
    assert changed != text
    striker.write_text(changed)

    scratch = tmp_path / "scratch"
    scratch.mkdir()
    old = versions.resolve("git:HEAD:team", scratch, cwd=repo)
    assert old.commit is not None and (old.folder / "agents.xabsl").is_file()
    assert (old.folder / "options" / "striker.xabsl").read_text() == text
    with pytest.raises(UsageError, match="unknown revision"):
        versions.resolve("git:nosuchrev:team", scratch, cwd=repo)
    with pytest.raises(UsageError, match="did not match"):
        versions.resolve("git:HEAD:nosuchdir", scratch, cwd=repo)
    with pytest.raises(UsageError, match="git:REV:PATH"):
        versions.resolve("git:HEAD", scratch, cwd=repo)

    cwd = Path.cwd()
    os.chdir(repo)
    try:
        code = run_cli(
            "team", "git:HEAD:team", "-n", "2", "--duration", "60", "--json", "--html", str(tmp_path / "r.html")
        )
    finally:
        os.chdir(cwd)
    summary = orjson.loads(capsys.readouterr().out)
    assert code == 0 and summary["played"] == 2
    rows = {(r["option"], r["state"]): r for r in summary["states"]}
    shoot = rows.get(("striker", "shoot"))
    assert shoot is None or shoot["home"] == 0.0  # the working tree never enters it
    page = (tmp_path / "r.html").read_text()
    assert page.startswith("<!doctype html>") and "git:HEAD:team" in page and "<script" not in page
    assert "src=" not in page and "href=" not in page  # self-contained


def test_usage_errors():
    with pytest.raises(UsageError, match="no such behavior folder"):
        run_cli("no/such/folder", str(DEFAULT_AWAY))
    with pytest.raises(SystemExit):
        run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "0")
    with pytest.raises(SystemExit):
        run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "--duration", "nan")


def test_a_behavior_with_errors_is_exit_1(tmp_path, capsys):
    (tmp_path / "agents.xabsl").write_text('agent broken("b", nosuchoption);\n')
    assert run_cli(str(tmp_path), str(DEFAULT_AWAY)) == 1
    assert "agents.xabsl" in capsys.readouterr().err


def test_ctrl_c_keeps_the_finished_matches(monkeypatch, capsys):
    # A real SIGINT, sent as soon as the first match is in: what a user's Ctrl+C does mid-run.
    update = cli._progress.update
    seen = []

    def interrupt_after_the_first(self, result):
        update(self, result)
        seen.append(result["index"])
        if len(seen) == 1:
            os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(cli._progress, "update", interrupt_after_the_first)
    start = time.perf_counter()
    code = run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "12", "--duration", "90", "-j", "2", "--json")
    elapsed = time.perf_counter() - start
    summary = orjson.loads(capsys.readouterr().out)
    assert code == 130
    assert summary["interrupted"] and summary["planned"] == 12
    assert 1 <= summary["played"] < 12 and summary["played"] == len(seen)
    assert summary["failed"] == []  # the matches running at Ctrl+C are neither results nor failures
    assert summary["results"]["wins"] + summary["results"]["draws"] + summary["results"]["losses"] == summary["played"]
    # The running matches stop within a simulated second instead of playing to the end, and the
    # ten matches not started are not played.
    assert elapsed < 60


def test_a_version_against_itself_is_exactly_even(capsys):
    # Each seed is played once each way round, so two equal versions get exactly the same totals:
    # a wrong colour mapping would give HOME the blue team's results twice.
    code = run_cli(str(DEFAULT_HOME), str(DEFAULT_HOME), "-n", "2", "--duration", "40", "-j", "2", "--json")
    summary = orjson.loads(capsys.readouterr().out)
    assert code == 0 and summary["played"] == 2
    assert summary["results"]["wins"] == summary["results"]["losses"]
    assert summary["goals"]["home"] == summary["goals"]["away"]
    assert summary["teams"]["home"] == summary["teams"]["away"]
    assert all(row["difference"] == 0.0 for row in summary["activations"] + summary["states"])
    first, second = summary["matches"]
    assert first["score"] == {"home": second["score"]["away"], "away": second["score"]["home"]}


def _result(index: int, activations: dict[str, dict[str, int]]) -> dict:
    return {
        "index": index,
        "ok": True,
        "seed": index + 1,
        "home_colour": "blue",
        "score": {"home": 1, "away": 0},
        "cpu_seconds": 1.0,
        "sim_seconds": 10.0,
        "teams": {side: dict.fromkeys(report.TEAM_STATS, 0) for side in ("home", "away")},
        "robot_ticks": {"home": 1000, "away": 1000},
        "activations": activations,
        "states": {side: {f"{o}/s": [n, 1] for o, n in activations[side].items()} for side in ("home", "away")},
        "faults": [],
        "trace_hash": "0",
    }


def test_the_biggest_difference_leads_the_terminal_and_the_html_report(capsys):
    """An option only one version runs (15.8 % vs 0 %) was last, below the +0.00 rows, and cut
    from the terminal's top rows (issue 23): it leads both, in one order."""
    common = {f"shared_{k:02d}": 500 + k for k in range(report.TOP + 3)}
    home = {**common, "shared_07": 530, "new_skill": 158}
    results = [_result(0, {"home": home, "away": dict(common)})]
    summary = report.summarize(results, home="a", away="b", planned=1, wall_seconds=1.0, jobs=1, backend="local pool")
    order = [row["option"] for row in summary["activations"]]
    assert order[:2] == ["new_skill", "shared_07"]
    assert summary["activations"][0]["home"] == 0.158 and summary["activations"][0]["away"] == 0.0
    report.print_report(summary)
    terminal = capsys.readouterr().out
    assert "new_skill (only HOME)" in terminal
    page = report.html_report(summary)
    shown = [name for name in order if f"<td>{name}" in page]
    assert sorted(shown, key=page.index) == order  # the HTML rows in the summary's order
    printed = [name for name in order[: report.TOP] if name in terminal]
    assert sorted(printed, key=terminal.index) == order[: report.TOP]
    states = [f"{row['option']}/{row['state']}" for row in summary["states"]]
    assert states[0] == "new_skill/s"


@pytest.mark.parametrize(
    ("name", "target", "why"),
    [
        ("options/secret.xabsl", "/etc/passwd", "absolute"),
        ("escape.xabsl", "../../outside.xabsl", "outside"),
    ],
)
def test_a_git_tree_with_a_link_out_of_it_is_a_usage_error(tmp_path, name, target, why):
    repo = tmp_path / "repo"
    shutil.copytree(DEFAULT_HOME, repo / "team")
    (repo / "outside.xabsl").write_text("/* not the team's */\n")
    (repo / "team" / name).symlink_to(target)
    _git(repo, "init", "-q")
    _git(repo, "add", ".")
    _git(repo, "commit", "-qm", "a link out")
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "tournament", "git:HEAD:team", str(DEFAULT_AWAY), "-n", "1"],
        cwd=repo,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
        check=False,
    )
    assert done.returncode == 2, done.stdout + done.stderr
    assert "Traceback" not in done.stderr and "Error" not in done.stderr, done.stderr
    assert "git:HEAD:team" in done.stderr and f"team/{name}" in done.stderr and why in done.stderr, done.stderr
    assert target in done.stderr


def test_record_keeps_every_match_and_the_report_links_each(tmp_path, capsys):
    """Every match's recording: both versions by name, their sources (for a fork), what the match scored."""
    from xabsl_studio.engine.record import Recording

    folder, page = tmp_path / "recorded", tmp_path / "report.html"
    argv = [str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "2", "--duration", "12", "-j", "2", "--json"]
    assert run_cli(*argv, "--record", str(folder), "--html", str(page)) == 0
    summary = orjson.loads(capsys.readouterr().out)
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["match-000-seed1-home-blue.mcap", "match-001-seed1-home-red.mcap"]
    for entry in summary["matches"]:
        path = Path(entry["recording"])
        assert path.parent == folder.resolve()
        with Recording(path) as recording:
            blue = "home" if entry["home_colour"] == "blue" else "away"
            red = "away" if blue == "home" else "home"
            assert {a: recording.program_key(a) for a in recording.agents} == {
                **{a: blue for a in recording.agents if a.startswith("blue")},
                **{a: red for a in recording.agents if a.startswith("red")},
            }
            assert all(recording.programs[(key, 0)].sources for key in ("home", "away"))
            status = list(recording.ticks())[-1].status
            assert [status["score"][0], status["score"][1]][0 if blue == "home" else 1] == entry["score"]["home"]
        assert f"href='recorded/{path.name}'" in page.read_text()  # relative to the report: the folder travels
    # recording does not change what is played
    assert run_cli(*argv) == 0
    plain = orjson.loads(capsys.readouterr().out)
    assert [m["trace_hash"] for m in plain["matches"]] == [m["trace_hash"] for m in summary["matches"]]


def test_a_failed_match_keeps_the_ticks_it_played(tmp_path):
    home, away = load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY)
    spec = match.plan(1, 3, 600.0, timeout_s=1.0, record_dir=tmp_path)[0]  # 10 minutes never fit in 1 s
    result = match.play(spec, home, away)
    assert not result["ok"] and "MatchTimeout" in result["error"]
    from xabsl_studio.engine.record import Recording

    with Recording(result["recording"]) as recording:
        assert len(recording) > 10  # what ran until the timeout, a readable recording


def test_record_refuses_a_cluster_of_other_machines(tmp_path):
    with pytest.raises(UsageError, match="where each match runs"):
        run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "1", "--record", str(tmp_path), "--ray", "127.0.0.1:6379")
