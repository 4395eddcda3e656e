"""Committed result files and the pages and figures made from them (`make results`).

`python -m experiments.results` writes docs/results/ and the README's headline figure from the JSON files here.
"""
