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
        listed = sorted(f for f in os.listdir(tmp_path / sub) if f.endswith(".py"))
        assert _shipped(sub) and listed == _shipped(sub), sub
    assert len(copied) == sum(len(_shipped(s)) for s in presets.SUBDIRS.values())
    wave = presets.SUBDIRS["wave"]
    edited = tmp_path / wave / _shipped(wave)[0]
    edited.write_text("# the artist's own\n")
    removed = tmp_path / wave / _shipped(wave)[1]
    removed.unlink()                                        # removed in Blender's preset menu
    assert presets.copy_presets(folder_of) == [] and not removed.exists()     # it stays removed (it came back)
    assert edited.read_text() == "# the artist's own\n"
    record = tmp_path / wave / presets.COPIED_RECORD        # a preset shipped later: copied once, at the next start
    record.write_text("".join(f"{n}\n" for n in _shipped(wave)[1:]))
    assert presets.copy_presets(folder_of) == []            # its name is taken by the artist's edit: kept
    record.write_text("".join(f"{n}\n" for n in _shipped(wave) if n != _shipped(wave)[2]))
    (tmp_path / wave / _shipped(wave)[2]).unlink()
    assert presets.copy_presets(folder_of) == [str(tmp_path / wave / _shipped(wave)[2])]
    assert presets.copy_presets(folder_of) == []
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
