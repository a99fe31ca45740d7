"""The tiny neural noise run the training tests share: trained and exported once per session."""
import pytest

from tiny_run import TINY


@pytest.fixture(scope="session")
def exported(tmp_path_factory):
    """A tiny trained run and its export in the default (split) form (read-only for the tests)."""
    pytest.importorskip("torch")
    pytest.importorskip("onnx")
    from omninoise.training.export_onnx import export
    from omninoise.training.train import TrainConfig, train

    run = tmp_path_factory.mktemp("run")
    out = tmp_path_factory.mktemp("model")
    train(TrainConfig.from_dict(TINY), str(run), log=lambda s: None)
    export(str(run), str(out))
    return run, out
