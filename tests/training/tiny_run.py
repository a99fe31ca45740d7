"""The tests' tiny neural noise configuration (tools/make_tiny_model.py trains the same); the run itself is the
session fixture ``exported`` of tests/training/conftest.py."""

TINY = dict(size=16, batch=4, steps=3, widths=(8, 16, 16), emb_dim=8, log_every=1, checkpoint_every=3, sample_every=0,
            classes=("perlin", "spots", "cells_f1"))
