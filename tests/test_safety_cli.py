"""Option and command typos: one line with the sub-command's usage and a suggestion, exit 2."""

import pytest

from openpbr_diffuse.cli.main import main


@pytest.mark.parametrize(
    "argv, expect",
    [
        (
            ["report", "--otu", "x"],
            ["openpbr-diffuse report: error:", "did you mean --out?", "usage: openpbr-diffuse report"],
        ),
        (
            ["simulate", "--geometry", "smith-ggx", "--roughness", "0.5", "--pahts", "10"],
            ["did you mean --paths?", "usage: openpbr-diffuse simulate"],
        ),
        (["reprot"], ["did you mean report?"]),
        (["simlate", "--paths", "3"], ["did you mean simulate?"]),
    ],
)
def test_typo_one_line_with_suggestion(capsys, argv, expect):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    for text in expect:
        assert text in err


def test_no_suggestion_when_nothing_is_close(capsys):
    assert main(["report", "--zzzzzz"]) == 2
    err = capsys.readouterr().err
    assert "did you mean" not in err and "usage: openpbr-diffuse report" in err


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_eval_time_must_be_finite(value):
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "openpbr_diffuse",
            "eval",
            str(root / "materials" / "velvet_animated.usda"),
            "--time",
            value,
        ],
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"},
    )
    assert p.returncode == 2 and "--time" in p.stderr and "finite" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
