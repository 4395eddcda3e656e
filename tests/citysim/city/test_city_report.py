"""The city report's sentences are read from the results, and its figures are drawn from city.json."""

from __future__ import annotations

import json

from citysim.report.city_report import map_sentence, ranking_sentence, write_city_report


def _city() -> dict:
    streets = []
    for i, (name, payback) in enumerate((("elm", 4.0), ("oak", 12.5), ("ash", None))):
        streets.append({"name": name, "lamps": 3 + i, "best": "pir" if payback else None,
                        "best_payback_years": payback, "best_npv": 100.0 if payback else None,
                        "centreline_m": [[0.0, -60.0 * i], [100.0, -60.0 * i]],
                        "lamps_m": [[20.0, 6.0 - 60.0 * i], [50.0, 6.0 - 60.0 * i]],
                        "controllers": {"pir": {"savings_vs_always_on": 0.5}}})  # fmt: skip
    ranking = [{"rank": k + 1, "street": s["name"], "controller": s["best"], "payback_years": s["best_payback_years"],
                "npv": s["best_npv"], "lit_on_entry_rate": 0.995 if s["best"] else None}
               for k, s in enumerate(streets)]  # fmt: skip
    return {"city": "toytown", "streets": streets, "ranking": ranking, "layout": "grid", "min_lit_on_entry": 0.99,
            "currency": "EUR", "year": 2025, "fidelity": "fast",
            "site": {"latitude_deg": 51.2, "longitude_deg": 6.8, "timezone": "Europe/Berlin"},
            "money": {"lifetime_years": 10, "price_per_kwh": 0.3, "price_change_per_year": 0.02,
                      "discount_rate": 0.03}}  # fmt: skip


def test_the_sentences_say_what_this_city_shows():
    city = _city()
    text = map_sentence(city)
    assert "1 of 3 streets pay back within the hardware's 10-year lifetime" in text
    assert "elm pays back soonest: 4.0 years with pir" in text
    assert "in a grid" in text
    assert "First elm (4.0 years), last ash (never)" in ranking_sentence(city)


def test_the_report_embeds_the_map_and_the_ranking(tmp_path):
    (tmp_path / "city.json").write_text(json.dumps(_city()))
    report, plots = write_city_report(tmp_path)
    page = report.read_text()
    assert [p.name for p in plots] == ["city_map.png", "city_ranking.png"]
    assert all(p.stat().st_size > 5000 for p in plots)
    assert page.count("data:image/png;base64,") == 2
    assert "pays back soonest" in page and "<td>oak</td>" in page
