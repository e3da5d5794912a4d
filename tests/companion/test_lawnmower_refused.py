"""A lawnmower profile (policy.kind lm1/lm2) is refused in the air, before anything starts:
the companion does not fly it yet (the Monte-Carlo engine does)."""

from __future__ import annotations

from pathlib import Path

import pytest

from companion.cli import main
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import builtin_profile, write_profile


@pytest.mark.parametrize("method", ["LM1", "LM2"])
@pytest.mark.parametrize("command", ["fleet", "run"])
def test_lawnmower_profile_is_refused(
    method: str, command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "lawnmower.yaml"
    write_profile(with_method(builtin_profile("field-duebendorf"), method), path)
    args = ["--profile", str(path), "--out", str(tmp_path / "run")]
    if command == "run":
        args = ["--profile", str(path), "--vehicle", "0", "--connect", "udpin:127.0.0.1:1"]
    assert main([command, *args]) == 2
    err = capsys.readouterr().err
    assert f"policy.kind '{method.lower()}' (the lawnmower baseline)" in err
    assert not (tmp_path / "run" / "run.json").exists()
