import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture
def scenes() -> pathlib.Path:
    return ROOT / "scenes"


@pytest.fixture(autouse=True)
def _no_display(monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    yield


def cli() -> pathlib.Path:
    """The command-line binary built by `cargo test --workspace --release` (tests/all.sh)."""
    path = pathlib.Path(os.environ.get("DALEMBERT_BIN", ROOT / "target" / "release" / "dalembert"))
    if not path.exists():
        pytest.fail(f"{path} not found: build it with `cargo build --release -p dalembert-cli` (tests/all.sh does)")
    return path
