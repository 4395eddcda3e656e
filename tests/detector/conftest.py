"""Every detector test keeps its trained-model cache in its own temporary folder, so no test reads
a model another test (or the user) cached, and none writes into the user's ~/.cache."""

import pytest


@pytest.fixture(autouse=True)
def _own_model_cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("CITYSIM_CACHE", str(tmp_path_factory.mktemp("cache")))
