"""`citysim validate` covers the street tracker's controllers: detector_fused and oracle_seen, full against fast."""

from __future__ import annotations

import re

import pytest

from citysim.cli import main


@pytest.mark.slow
def test_validate_compares_detector_fused_and_oracle_seen_full_against_fast(capsys):
    # suburban_night ships its sensor model, so this renders 20 s of 11 cameras and runs the same
    # night fast; the figures themselves are measured at length in docs/design/fusion.md
    code = main(["validate", "scenarios/suburban_night.yaml", "--duration", "20", "--seeds", "1",
                 "--controllers", "oracle_seen,detector_fused", "--workers", "1", "--no-progress"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0
    rows = {line.split()[0]: line for line in out.splitlines() if line.split()[:1] in (["oracle_seen"], ["detector_fused"])}
    assert set(rows) == {"oracle_seen", "detector_fused"}
    for line in rows.values():
        # savings full / fast: both measured, each a percentage, and a verdict on every figure
        assert re.search(r"-?\d+\.\d% / -?\d+\.\d% (PASS|MISS)", line), line
        assert len(re.findall(r"\b(PASS|MISS)\b", line)) == 4, line
    assert re.search(r"\d+ of \d+ cells agree", out)
