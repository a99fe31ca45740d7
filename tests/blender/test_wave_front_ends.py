"""One wave request for every front-end: the command line's flags, a job file's source table and the
Wave Noise node's panel give the same frozen WaveSettings for the same settings."""
import pytest

bpy = pytest.importorskip("bpy")

from omninoise import blender_addon  # noqa: E402
from omninoise.backend.sources import source_from_dict  # noqa: E402
from omninoise.cli.main import build_parser  # noqa: E402
from omninoise.cli.wave import settings_from_args  # noqa: E402

CASES = [
    # (flags, job-file table, panel properties)
    (["--dim", "3", "--spectrum", "bandpass", "--fmin", "3", "--fmax", "7", "--directions", "12", "--seed", "5"],
     {"dim": 3, "spectrum": "bandpass", "fmin": 3.0, "fmax": 7.0, "directions": 12, "seed": 5},
     dict(dimensions="3", spectrum="bandpass", fmin=3.0, fmax=7.0, directions=12, seed=5)),
    (["--dim", "2", "--spectrum", "fractal", "--fmin", "1", "--fmax", "16", "--exponent", "1.5", "--waveform",
      "crystal", "--speed", "0.5"],
     {"dim": 2, "spectrum": {"kind": "fractal", "fmin": 1.0, "fmax": 16.0, "exponent": 1.5}, "waveform": "crystal",
      "speed": 0.5},
     dict(dimensions="2", spectrum="fractal", fmin=1.0, fmax=16.0, exponent=1.5, waveform="crystal", speed=0.5)),
    (["--dim", "3", "--anisotropy", "lobes", "--lobe", "1,0,0:1", "--spread", "25"],
     {"dim": 3, "anisotropy": "lobes", "lobes": [[[1, 0, 0], 1.0]], "spread": 25.0},
     dict(dimensions="3", anisotropy="lobes", axis=(1.0, 0.0, 0.0), spread=25.0)),
]


@pytest.fixture(scope="module", autouse=True)
def addon():
    blender_addon.register()
    yield
    blender_addon.unregister()


@pytest.mark.parametrize("flags, table, props", CASES)
def test_flags_job_tables_and_the_panel_give_equal_settings(flags, table, props):
    cli = settings_from_args(build_parser().parse_args(["wave", *flags, "-o", "x.npy"]))
    job = source_from_dict(dict(table), ".").settings
    bpy.ops.wm.read_homefile(use_empty=True)
    tree = bpy.data.node_groups.new("Wave", "ShaderNodeTree")
    p = tree.omninoise_wave
    for k, v in props.items():
        setattr(p, k, v)
    panel = p.to_settings()
    assert cli == job, (cli, job)
    assert panel == cli, (panel, cli)


@pytest.mark.parametrize("flags, props", [
    (["--cellular", "stit", "--cell-size", "0.375", "--stit-probability", "0.75", "--stit-depth", "2"],
     dict(cellular="stit", cell_size=0.375, stit_probability=0.75, stit_depth=2)),
    (["--cellular", "polytope"], dict(cellular="polytope")),        # Cell Size 0: from the band, as the flag's default
    (["--cellular", "code", "--cell-size", "1.5"], dict(cellular="code", cell_size=1.5, stit_depth=5)),
])
def test_the_bake_panels_cells_are_the_command_lines(flags, props):
    """The Bake Noise panel's Cellular, Cell Size and STIT split settings give the command line's settings (the
    split settings only where STIT reads them)."""
    from omninoise.blender_addon import bake_ui

    bpy.ops.wm.read_homefile(use_empty=True)
    p = bpy.context.scene.omninoise_bake
    p.wave.dimensions, p.wave.fmin, p.wave.fmax = "2", 2.0, 6.0
    for k, v in props.items():
        setattr(p, k, v)
    cli = settings_from_args(build_parser().parse_args(["wave", "--fmin", "2", "--fmax", "6", *flags, "-o", "x.npy"]))
    assert bake_ui._settings(p) == cli
