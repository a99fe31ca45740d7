"""Where a Blender lacks ``bpy.utils.register_preset_path`` (4.2.0), the shipped presets are copied into the
user's presets folder (``blender_addon.presets.copy_presets``); Blender-free: the folders are the test's."""
import os

from omninoise.blender_addon import presets


def _shipped(sub: str) -> list:
    return sorted(f for f in os.listdir(os.path.join(presets.ROOT, "presets", sub)) if f.endswith(".py"))


def test_every_shipped_preset_is_copied_and_an_artists_edit_stays(tmp_path, capsys):
    def folder_of(sub):
        path = tmp_path / sub
        path.mkdir(parents=True, exist_ok=True)
        return str(path)

    copied = presets.copy_presets(folder_of)
    for sub in presets.SUBDIRS.values():
        assert _shipped(sub) and sorted(os.listdir(tmp_path / sub)) == _shipped(sub), sub
    assert len(copied) == sum(len(_shipped(s)) for s in presets.SUBDIRS.values())
    wave = presets.SUBDIRS["wave"]
    edited = tmp_path / wave / _shipped(wave)[0]
    edited.write_text("# the artist's own\n")
    (tmp_path / wave / _shipped(wave)[1]).unlink()         # removed in Blender's preset menu
    again = presets.copy_presets(folder_of)
    assert again == [str(tmp_path / wave / _shipped(wave)[1])]          # back, and only it
    assert edited.read_text() == "# the artist's own\n"
    assert capsys.readouterr().out == ""


def test_a_folder_that_cannot_be_made_leaves_its_kind_out_and_says_so(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)

    def folder_of(sub):
        if sub == presets.SUBDIRS["neural"]:
            raise PermissionError(13, "Permission denied", "/read-only/presets")
        if sub == presets.SUBDIRS["solid"]:
            return ""               # what Blender's user_resource gives where it could not make the folder
        path = tmp_path / sub
        path.mkdir(parents=True, exist_ok=True)
        return str(path)

    copied = presets.copy_presets(folder_of)
    assert not (tmp_path / presets.SUBDIRS["neural"]).exists()
    assert len(copied) == sum(len(_shipped(s)) for k, s in presets.SUBDIRS.items() if k not in ("neural", "solid"))
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".py")]          # nothing in the working folder
    assert capsys.readouterr().out == ("OmniNoise: the shipped neural presets are not available: [Errno 13] "
                                       "Permission denied: '/read-only/presets'\n"
                                       "OmniNoise: the shipped solid presets are not available: no folder ''\n")
