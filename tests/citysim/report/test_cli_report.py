"""`citysim run` ends with report.html in the run folder and says where everything is;
`citysim plot` writes the report from the plots it drew."""

from __future__ import annotations

from pathlib import Path

from citysim.cli import main
from citysim.report import run_plots
from citysim.report.run_plots import RUN_PLOTS


def test_run_writes_report_html_and_prints_where_things_are(scenario_file, tmp_path, capsys):
    out = tmp_path / "demo"
    args = ["run", str(scenario_file), "--out", str(out), "--duration", "6", "--controllers", "always_on,pir",
            "--workers", "1", "--no-progress"]  # fmt: skip
    assert main(args) == 0
    report = out / "report.html"
    assert report.exists()
    page = report.read_text()
    assert all(f'alt="{name}"' in page for name in RUN_PLOTS)
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-1].endswith(str(report))  # the last thing printed: where to look
    printed = "\n".join(lines)
    assert str(out / "summary.json") in printed and f"{out / 'plots'}/" in printed


def test_plot_draws_each_plot_once_and_reports(run_copy, capsys, monkeypatch):
    calls = []
    plot_run = run_plots.plot_run

    def counted(folder):
        calls.append(Path(folder))
        return plot_run(folder)

    monkeypatch.setattr(run_plots, "plot_run", counted)
    assert main(["plot", str(run_copy)]) == 0
    assert calls == [run_copy]
    assert f"report: {run_copy / 'report.html'}" in capsys.readouterr().out
