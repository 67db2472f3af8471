"""The `shadowhound` command as users run it: a real process, real stdout/stderr/exit codes."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data"


def shadowhound(*args, stdin=None, env=None):
    full_env = {**os.environ, **(env or {})}
    full_env.pop("SHADOWHOUND_CONFIG", None)
    return subprocess.run([sys.executable, "-m", "shadowhound", *args], capture_output=True,
                          text=True, input=stdin, timeout=60, env=full_env)


def test_run_json_prints_exactly_one_object():
    proc = shadowhound("run", "--json", "rotate 90 degrees")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)  # exactly one JSON document, nothing else on stdout
    assert out["success"] is True
    assert out["robot"]["yaw"] == 1.5708
    assert set(out["robot"]) >= {"x", "y", "yaw", "posture", "battery", "distance_travelled",
                                 "angle_turned"}
    assert out["steps"][0]["skill"] == "nav.rotate"
    assert set(out["timing"]) >= {"agent_duration", "total_duration", "overhead_duration",
                                  "agent_percentage"}
    assert out["usage"]["total_tokens"] == 0
    assert "nav.rotate" in proc.stderr  # progress goes to stderr


def test_run_human_output_and_failure_exit_code():
    proc = shadowhound("run", "stand up and walk forward 1.5 meters")
    assert proc.returncode == 0
    assert "Done:" in proc.stdout and "x=1.50" in proc.stdout
    proc = shadowhound("run", "--quiet", "blorp the zanzibar")
    assert proc.returncode == 1
    assert "not understand" in proc.stdout.lower() or "didn't understand" in proc.stdout.lower()
    assert proc.stderr == ""


def test_refused_mission_exits_1_with_reason():
    proc = shadowhound("run", "--json", "walk forward 500 meters")
    assert proc.returncode == 1
    out = json.loads(proc.stdout)
    assert out["success"] is False and out["robot"]["distance_travelled"] == 0
    assert "limit" in out["response"]


def test_usage_and_config_errors_exit_2(tmp_path):
    assert shadowhound("run").returncode == 2
    assert shadowhound().returncode == 2
    proc = shadowhound("--config", "nope", "run", "stand up")
    assert proc.returncode == 2 and "unknown config profile 'nope'" in proc.stderr
    bad = tmp_path / "bad.yaml"
    bad.write_text("safety: {max_linear_speed: fast}")
    proc = shadowhound("run", "--config", str(bad), "stand up")
    assert proc.returncode == 2 and "safety.max_linear_speed" in proc.stderr
    proc = shadowhound("run", "--backend", "openai", "stand up", env={"OPENAI_API_KEY": ""})
    assert proc.returncode == 2 and "set the environment variable OPENAI_API_KEY" in proc.stderr


def test_skills_listing_and_json():
    proc = shadowhound("skills")
    assert proc.returncode == 0 and "nav.move(distance, speed?)" in proc.stdout
    skills = json.loads(shadowhound("skills", "--json").stdout)
    move = next(s for s in skills if s["name"] == "nav.move")
    assert move["parameters"]["properties"]["distance"]["type"] == "number"


def test_chat_repl_from_stdin():
    proc = shadowhound("chat", stdin="where are you?\n/run walk forward 1 meter\nwhere are you?\n"
                                     "/bogus\n/quit\n")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert "x=0.00 m" in lines[0]
    assert lines[1].startswith("ok: Done: moved 1.00 m forward")
    assert "x=1.00 m" in lines[2]
    assert "unknown command '/bogus'" in lines[3]


def test_eval_public_cases_all_pass():
    proc = shadowhound("eval", str(DATA / "missions_public.yaml"))
    assert proc.returncode == 0, proc.stdout
    assert proc.stdout.strip().splitlines()[-1].endswith("cases passed (100.0%)")


def test_eval_json_and_failing_cases(tmp_path):
    cases = tmp_path / "cases.yaml"
    cases.write_text('- mission: "walk forward 1 meter"\n  expect: {x: 2.0, moved: true}\n'
                     '- mission: "sit down"\n  expect: {posture: sitting}\n')
    proc = shadowhound("eval", "--json", str(cases))
    assert proc.returncode == 1
    report = json.loads(proc.stdout)
    assert (report["passed"], report["failed"]) == (1, 1)
    assert report["cases"][0]["failures"] == ["x: expected 2.0, got 1.0006"]


@pytest.mark.parametrize(("content", "message"), [
    ("mission: x", "must be a YAML list"),
    ("- {expect: {}}", "case 1"),
    ("- {mission: hi, expect: {z: 1}}", "unknown expect keys ['z']"),
    ("- {mission: hi, expect: {x: far}}", "expect.x must be a number"),
])
def test_eval_bad_case_file(tmp_path, content, message):
    cases = tmp_path / "cases.yaml"
    cases.write_text(content)
    proc = shadowhound("eval", str(cases))
    assert proc.returncode == 2 and message in proc.stderr


def test_config_command_shows_no_secrets():
    proc = shadowhound("config", env={"OPENAI_API_KEY": "sk-secret-123"})
    assert proc.returncode == 0 and "max_linear_speed: 0.5" in proc.stdout
    assert "sk-secret-123" not in proc.stdout


def test_run_dry_run_shows_plan_and_path_without_moving():
    proc = shadowhound("run", "--dry-run", "walk forward 1 meter then come back")
    assert proc.returncode == 0
    assert "[1] nav.move(distance=1.0)" in proc.stdout and "predicted path:" in proc.stdout
    assert "nothing moved" in proc.stdout
    out = json.loads(shadowhound("run", "--dry-run", "--json", "walk forward 9 meters").stdout)
    assert out["dry_run"] and not out["success"] and out["robot"]["distance_travelled"] == 0


def test_risky_trick_needs_approval_on_the_command_line():
    refused = shadowhound("run", "-q", "do a backflip")  # no terminal: nobody to ask
    assert refused.returncode == 1 and "no interface that can ask a person" in refused.stdout
    approved = shadowhound("run", "-q", "--yes", "do a backflip")
    assert approved.returncode == 0 and "performed backflip" in approved.stdout
