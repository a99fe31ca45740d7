"""One reader for every image input: files of any depth by their own range, broken files refused in
one line naming the file, and the CLI turning each into exit 2."""
import struct
import zlib

import numpy as np
import pytest
from PIL import Image

from omninoise.cli.main import main
from omninoise.export.images import MAX_PIXELS, ImageError, decode, read_image, read_rgb


def _png16(path, a):
    Image.fromarray(a.astype(np.uint16)).save(path)


def _huge_png(path, w, h):
    """A valid-looking PNG whose header claims w x h pixels (its data is one row)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    raw = zlib.compress(b"\x00" * (w + 1))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                     + chunk(b"IDAT", raw) + chunk(b"IEND", b""))


def test_sixteen_bit_images_are_read_by_their_range(tmp_path):
    m = np.zeros((20, 20), np.uint16)
    m[:, :11] = 65535                                     # 55% white
    _png16(tmp_path / "mask16.png", m)
    a = read_image(str(tmp_path / "mask16.png"))
    assert a.dtype == np.float32 and a.max() == pytest.approx(1.0) and (a > 0.5).mean() == pytest.approx(0.55)
    g = np.full((8, 8), 30000, np.uint16)
    _png16(tmp_path / "grey16.png", g)
    assert read_rgb(str(tmp_path / "grey16.png"))[0, 0, 0] == pytest.approx(30000 / 65535, abs=1e-6)
    Image.fromarray(np.full((4, 4, 3), 51, np.uint8)).save(tmp_path / "rgb8.png")
    assert read_rgb(str(tmp_path / "rgb8.png")).shape == (4, 4, 3)
    assert read_image(str(tmp_path / "rgb8.png"))[0, 0] == pytest.approx(0.2)


def _chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def _adam7_png16(path, a):
    """An interlaced (Adam7) 16-bit RGB PNG of uint16 (H, W, 3): each pass's rows unfiltered."""
    h, w, _ = a.shape
    rows = b""
    for y0, x0, dy, dx in ((0, 0, 8, 8), (0, 4, 8, 8), (4, 0, 8, 4), (0, 2, 4, 4), (2, 0, 4, 2), (0, 1, 2, 2),
                           (1, 0, 2, 1)):
        sub = a[y0::dy, x0::dx].astype(">u2")
        if sub.size:
            rows += b"".join(b"\x00" + r.tobytes() for r in sub)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 1))
                     + _chunk(b"IDAT", zlib.compress(rows)) + _chunk(b"IEND", b""))


def _tiff16(path, a, order):
    """An uncompressed 16-bit RGB TIFF of uint16 (H, W, 3), in byte order ``order`` ("<" Intel, ">" Motorola)."""
    h, w, _ = a.shape
    data = a.astype(order + "u2").tobytes()
    entries = [(256, 3, 1, w), (257, 3, 1, h), (258, 3, 3, 8 + 2 + 12 * 10 + 4), (259, 3, 1, 1), (262, 3, 1, 2),
               (273, 4, 1, 8 + 2 + 12 * 10 + 4 + 6), (277, 3, 1, 3), (278, 3, 1, h), (279, 4, 1, len(data)),
               (284, 3, 1, 1)]
    ifd = struct.pack(order + "H", len(entries)) + b"".join(
        struct.pack(order + "HHI", tag, kind, n) + (struct.pack(order + "HH", v, 0) if kind == 3 and n == 1 else
                                                     struct.pack(order + "I", v)) for tag, kind, n, v in entries)
    head = (b"II*\x00" if order == "<" else b"MM\x00*") + struct.pack(order + "I", 8)
    path.write_bytes(head + ifd + struct.pack(order + "I", 0) + struct.pack(order + "HHH", 16, 16, 16) + data)


def _tiff32(path, a, signed):
    """A grey TIFF of 32-bit samples, signed or unsigned (its SampleFormat), little-endian, one strip."""
    h, w = a.shape
    data = a.astype("<i4" if signed else "<u4").tobytes()
    entries = [(256, 1, w), (257, 1, h), (258, 1, 32), (259, 1, 1), (262, 1, 1), (273, 1, 8 + 2 + 12 * 10 + 4),
               (277, 1, 1), (278, 1, h), (279, 1, len(data)), (339, 1, 2 if signed else 1)]
    ifd = struct.pack("<H", len(entries)) + b"".join(struct.pack("<HHII", tag, 4, n, v) for tag, n, v in entries)
    path.write_bytes(b"II*\x00" + struct.pack("<I", 8) + ifd + struct.pack("<I", 0) + data)


def test_thirty_two_bit_integer_files_are_read_by_their_type(tmp_path):
    """A 32-bit integer TIFF is divided by its type's largest value, as Blender and OpenImageIO read it (a quarter,
    a half and three quarters of the range are 0.25, 0.5 and 0.75), whatever values it holds: an unsigned file's
    upper half is no negative number, and small values are dark, not a 16-bit file's."""
    for signed, full in ((True, 2 ** 31 - 1), (False, 2 ** 32 - 1)):
        a = np.round(np.array([[0.25, 0.5], [0.75, 1.0]]) * full)
        _tiff32(tmp_path / "wide.tif", np.repeat(np.repeat(a, 8, 0), 8, 1), signed)
        got = read_rgb(str(tmp_path / "wide.tif"))
        assert got.shape == (16, 16, 3) and np.allclose(got[::8, ::8, 0], [[0.25, 0.5], [0.75, 1.0]], atol=1e-6)
        _tiff32(tmp_path / "small.tif", np.full((4, 4), 40000), signed)
        assert read_image(str(tmp_path / "small.tif")).max() == pytest.approx(40000 / full)


def test_sixteen_bit_colour_files_keep_all_sixteen_bits(tmp_path):
    """A 16-bit RGB, RGBA or grey-and-alpha PNG (interlaced too) and a 16-bit RGB TIFF of either byte order are read
    sample for sample (Pillow opens them as 8-bit colour, each sample's high byte: 0.4 % of the range lost, and a
    16-bit photo would differ from the same photo in Blender); write_png writes 16-bit PNGs."""
    from omninoise.export.images import write_png

    rng = np.random.default_rng(5)
    rgb = rng.integers(0, 65536, (13, 21, 3)).astype(np.uint16)
    opaque = np.full((13, 21, 1), 65535, np.uint16)
    cases = {"rgb.png": rgb, "rgba.png": np.concatenate([rgb, opaque], -1),
             "la.png": np.concatenate([rgb[..., :1], opaque], -1), "grey.png": rgb[..., 0]}
    for name, a in cases.items():
        write_png(str(tmp_path / name), a)
        assert np.array_equal(decode(str(tmp_path / name)), (a.reshape(a.shape[:2] + (-1,)) / np.float32(65535))
                              .astype(np.float32)), name
    _adam7_png16(tmp_path / "adam7.png", rgb)
    for order in "<>":
        _tiff16(tmp_path / f"tiff{order == '<'}.tif", rgb, order)
    for name in ("adam7.png", "tiffTrue.tif", "tiffFalse.tif"):
        assert np.array_equal(decode(str(tmp_path / name)), rgb / np.float32(65535)), name
    assert np.array_equal(read_rgb(str(tmp_path / "la.png")), np.repeat(rgb[..., :1], 3, -1) / np.float32(65535))
    assert np.array_equal(read_rgb(str(tmp_path / "rgba.png")), rgb / np.float32(65535))
    exif = Image.Exif()         # a 16-bit photo with an EXIF orientation (6: turned) is turned too
    exif[0x0112] = 6
    data = (tmp_path / "rgb.png").read_bytes()
    at = data.index(b"IDAT") - 4
    (tmp_path / "turned.png").write_bytes(data[:at] + _chunk(b"eXIf", exif.tobytes()[6:]) + data[at:])
    assert np.array_equal(read_rgb(str(tmp_path / "turned.png")), np.rot90(rgb, -1) / np.float32(65535))


def test_float_files_hold_scene_linear_colour_and_exemplars_read_them_as_blender_shows_them(tmp_path):
    """A photo saved as EXR, float TIFF or float .npy (scene-linear, as the solid textures' own float outputs are)
    reads as the same sRGB pixels as its 8-bit PNG: an exemplar is the same photo in any file; 8- and 16-bit files
    keep their stored values."""
    from omninoise.backend.colour import srgb_to_linear
    from omninoise.export.images import write_exr

    rng = np.random.default_rng(3)
    srgb8 = rng.integers(0, 256, (24, 32, 3)).astype(np.uint8)
    Image.fromarray(srgb8).save(tmp_path / "photo.png")
    png = read_rgb(str(tmp_path / "photo.png"))
    assert np.array_equal(png, srgb8 / np.float32(255))
    linear = srgb_to_linear(png)
    write_exr(str(tmp_path / "photo.exr"), linear)
    np.save(tmp_path / "photo.npy", linear)
    for name in ("photo.exr", "photo.npy"):
        got = read_rgb(str(tmp_path / name))
        assert got.dtype == np.float32 and np.abs(got - png).max() < 1e-5, name
        assert abs(float(decode(str(tmp_path / name)).mean()) - float(linear.mean())) < 1e-6  # decode: as stored
    np.save(tmp_path / "photo8.npy", srgb8)                               # 8-bit arrays read as 8-bit files
    assert np.array_equal(read_rgb(str(tmp_path / "photo8.npy")), png)
    np.save(tmp_path / "photo16.npy", srgb8.astype(np.uint16) * 257)
    assert np.abs(read_rgb(str(tmp_path / "photo16.npy")) - png).max() < 1e-6
    Image.fromarray(linear[..., 1]).save(tmp_path / "green.tif")          # a float TIFF (one channel)
    assert np.abs(read_rgb(str(tmp_path / "green.tif"))[..., 0] - png[..., 1]).max() < 1e-5
    hdr = linear * 4.0                                                      # highlights above 1 clip, as in Blender
    write_exr(str(tmp_path / "hdr.exr"), hdr)
    assert read_rgb(str(tmp_path / "hdr.exr")).max() <= 1.0


def test_a_float_photo_of_whole_numbers_above_1_is_refused_naming_the_fix(tmp_path, capsys):
    """An 8-bit photo saved by numpy as floats (0 to 255) read as scene-linear colour came out white; it is refused
    in one line saying how to store it, as a file and through the command line (exit 2, nothing written). Whole
    numbers up to 1 (a mask of 0 and 1) and an HDR image's fractional highlights are colour as before."""
    from omninoise.export.images import write_exr

    srgb8 = np.random.default_rng(3).integers(0, 256, (32, 32, 3)).astype(np.float32)
    np.save(tmp_path / "f255.npy", srgb8)
    write_exr(str(tmp_path / "f255.exr"), srgb8)
    for name in ("f255.npy", "f255.exr"):
        with pytest.raises(ImageError, match=r"f255\.\w+: a float image holds scene-linear colour \(0 to 1, more "
                                             r"only in highlights\), but this one holds whole numbers up to 255, "
                                             r"as 8- or 16-bit pixels do: store them as uint8 or uint16, or divided "
                                             r"by 255"):
            read_rgb(str(tmp_path / name))
    out = tmp_path / "o.png"
    assert main(["solid", "--exemplar", str(tmp_path / "f255.npy"), "--method", "spectral", "-o", str(out)]) == 2
    assert "--exemplar: " in capsys.readouterr().err and not out.exists()
    np.save(tmp_path / "mask.npy", (srgb8 > 127).astype(np.float32))
    assert np.allclose(np.unique(read_rgb(str(tmp_path / "mask.npy"))), [0.0, 1.0])
    np.save(tmp_path / "hdr.npy", srgb8 / 100.0)
    assert abs(read_rgb(str(tmp_path / "hdr.npy")).max() - 1.0) < 1e-6


@pytest.mark.parametrize("make, match", [
    (lambda p: p.write_bytes(b""), "empty file"),
    (lambda p: p.write_text("hello, not an image"), "not an image file"),
    (lambda p: p.write_bytes((lambda b: b[: len(b) // 2])(_png_bytes())), "cannot read the image"),
    (lambda p: _huge_png(p, 40000, 40000), "more than the"),
])
def test_broken_images_are_refused_in_one_line(tmp_path, make, match):
    p = tmp_path / "bad.png"
    make(p)
    with pytest.raises(ImageError, match=match) as exc:
        decode(str(p))
    assert str(p) in str(exc.value) and "\n" not in str(exc.value)


def _png_bytes():
    import io
    buf = io.BytesIO()
    Image.fromarray(np.random.default_rng(0).integers(0, 255, (64, 64, 3), dtype=np.uint8)).save(buf, "PNG")
    return buf.getvalue()


def test_bad_npy_inputs(tmp_path):
    (tmp_path / "corrupt.npy").write_bytes(b"\x93NUMPY garbage")
    with pytest.raises(ImageError, match="corrupt.npy: cannot read"):
        decode(str(tmp_path / "corrupt.npy"))
    np.save(tmp_path / "nan.npy", np.array([[0.0, np.nan]], np.float32))
    with pytest.raises(ImageError, match="NaN or infinite"):
        decode(str(tmp_path / "nan.npy"))
    for dtype in (np.int32, np.int64, np.int8, np.uint32):      # 0..255 in int32 was read clipped, all white
        np.save(tmp_path / "ints.npy", np.full((4, 4, 3), 200, dtype) if dtype != np.int8 else np.ones((4, 4), dtype))
        with pytest.raises(ImageError, match=f"ints.npy: a .npy image of {np.dtype(dtype)} has no range; save it as "
                                             r"uint8 \(0 to 255\), uint16 \(0 to 65535\) or floats"):
            decode(str(tmp_path / "ints.npy"))
    np.save(tmp_path / "wide.npy", np.full((4, 4), 1e300))
    with pytest.raises(ImageError, match="NaN or infinite"):
        decode(str(tmp_path / "wide.npy"))
    np.save(tmp_path / "mask.npy", np.eye(4, dtype=bool))
    np.testing.assert_array_equal(decode(str(tmp_path / "mask.npy"))[..., 0], np.eye(4))
    np.save(tmp_path / "cube.npy", np.zeros((4, 4, 4, 4), np.float32))
    with pytest.raises(ImageError, match="expected an image"):
        decode(str(tmp_path / "cube.npy"))
    assert MAX_PIXELS == 1 << 27


def test_cli_image_inputs_exit_2(tmp_path, capsys):
    (tmp_path / "t.png").write_bytes(_png_bytes()[:300])
    rc = main(["wave", "--size", "16", "--quiet", "--example", str(tmp_path / "t.png"), "-o", str(tmp_path / "o.png")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(err) == 1 and "t.png" in err[0]
    assert not (tmp_path / "o.png").exists()


@pytest.mark.parametrize("orientation, turn", [(1, lambda a: a), (3, lambda a: a[::-1, ::-1]),
                                               (6, lambda a: np.rot90(a, -1)), (8, lambda a: np.rot90(a, 1)),
                                               (2, lambda a: a[:, ::-1]), (4, lambda a: a[::-1]),
                                               (5, lambda a: np.swapaxes(a, 0, 1)),
                                               (7, lambda a: np.swapaxes(a, 0, 1)[::-1, ::-1])])
def test_exif_orientation_turns_a_photo_as_viewers_show_it(tmp_path, orientation, turn):
    """A phone photo taken upright stores the sensor's rows and an EXIF orientation; it is read turned (a
    portrait brick photo keeps level courses), and one without the tag is read as stored."""
    rng = np.random.default_rng(orientation)
    stored = np.zeros((24, 40, 3), np.uint8)
    stored[:, :8] = 255                                     # a white band along the stored left edge
    stored[20:, :, 1] = rng.integers(0, 255, (4, 40))       # and a noisy stored bottom row
    path = str(tmp_path / f"o{orientation}.png")
    exif = Image.Exif()
    exif[0x0112] = orientation
    Image.fromarray(stored).save(path, exif=exif)
    want = turn(stored.astype(np.float32) / 255.0)
    got = read_rgb(path)
    assert got.shape == want.shape and np.array_equal(got, want)
    from PIL import ImageOps

    with Image.open(path) as im:        # as Pillow turns it
        assert np.array_equal(np.asarray(ImageOps.exif_transpose(im)), turn(stored))
    assert read_image(path).shape == want.shape[:2]


def test_partly_transparent_inputs_are_refused_and_opaque_alpha_is_dropped(tmp_path, capsys):
    """What lies under a transparent pixel is no colour of the picture (a cutout's is black here): an input with
    alpha below 1 anywhere is refused in one line with its share; an alpha of 255 everywhere is read as RGB."""
    rng = np.random.default_rng(3)
    rgba = np.concatenate([rng.integers(0, 255, (40, 40, 3)), np.full((40, 40, 1), 255)], axis=2).astype(np.uint8)
    Image.fromarray(rgba, "RGBA").save(tmp_path / "opaque.png")
    assert np.array_equal(read_rgb(str(tmp_path / "opaque.png")), rgba[..., :3] / np.float32(255.0))
    assert read_image(str(tmp_path / "opaque.png")).shape == (40, 40)
    rgba[:10, :, :3], rgba[:10, :, 3] = 0, 0                 # a cut-out top quarter
    rgba[10, 0, 3] = 254                                     # and one pixel just short of opaque
    Image.fromarray(rgba, "RGBA").save(tmp_path / "cut.png")
    grey = np.stack([rgba[..., 0], np.full((40, 40), 255, np.uint8)], axis=2)
    grey[0, 0, 1] = 128
    Image.fromarray(grey, "LA").save(tmp_path / "grey_cut.png")
    for name, share in (("cut.png", "25.1 %"), ("grey_cut.png", "0.0625 %")):
        for read in (read_rgb, read_image):
            with pytest.raises(ImageError, match="partly transparent") as exc:
                read(str(tmp_path / name))
            assert share in str(exc.value) and name in str(exc.value) and "\n" not in str(exc.value)
    rc = main(["solid", "--method", "spectral", "--dim", "2", "--size", "32", "--quiet",
               "--exemplar", str(tmp_path / "cut.png"), "-o", str(tmp_path / "o.png")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert rc == 2 and len(err) == 1 and "partly transparent" in err[0]
    assert not (tmp_path / "o.png").exists()


@pytest.mark.parametrize("argv, flag", [
    (["wave", "--size", "8", "--example"], "--example"),
    (["neural", "--size", "16", "--steps", "1", "--noise", "perlin", "--noise2", "cells_f1", "--blend"], "--blend"),
    (["neural", "--size", "16", "--steps", "1", "--fit"], "--fit"),
])
def test_an_unusable_image_is_named_by_its_flag(tmp_path, capsys, argv, flag):
    """A cut-out and a flat grey image: refused in one line that names the flag they were given to, before any
    work (by-example noise checks its image's size and contrast with its settings)."""
    rgba = np.full((16, 16, 4), 255, np.uint8)
    rgba[:4, :, 3] = 0
    Image.fromarray(rgba, "RGBA").save(tmp_path / "cut.png")
    Image.fromarray(np.full((16, 16), 128, np.uint8)).save(tmp_path / "flat.png")
    for name, why in (("cut.png", "partly transparent"), ("flat.png", "")):
        rc = main(argv + [str(tmp_path / name), "--quiet", "-o", str(tmp_path / "o.png")])
        err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
        if name == "flat.png" and flag == "--blend":
            assert rc == 0                       # a flat mask is one noise everywhere
            continue
        assert rc == 2 and len(err) == 1 and f"error: {flag}" in err[0] and why in err[0], err


@pytest.mark.parametrize("example, why", [
    (np.full((32, 32), np.nan), "NaN or infinite"),
    (np.full((32, 32), True), "image of numbers, got bool"),
    (np.zeros((32, 32, 3)), r"2D grayscale image of at least 16x16, got shape \(32, 32, 3\)"),
    (np.zeros((8, 64)), "at least 16x16"),
    (np.full((32, 32), 0.5), "the image is constant"),
])
def test_a_by_example_array_is_checked_with_the_settings(example, why):
    """omninoise.wave(example=...) takes a grey array: one that is not usable is refused, naming ``example``, as
    the settings are checked (NaN was refused later, as the "samples" of a custom spectrum no one gave)."""
    import omninoise
    from omninoise.backend.errors import SettingError

    with pytest.raises(SettingError, match=why) as exc:
        omninoise.wave(16, example=example)
    assert exc.value.setting == "example"
    assert np.isfinite(omninoise.wave(16, example=np.random.default_rng(0).random((32, 32)))).all()


def _float_rgb_tiff(path, h: int = 4, w: int = 4) -> None:
    """An uncompressed little-endian TIFF of three 32-bit float channels (SampleFormat 3), as a renderer saves
    one; Pillow reads one float channel only."""
    import struct

    pixels = np.full((h, w, 3), 0.5, "<f4").tobytes()
    tags = [(256, 3, 1, w), (257, 3, 1, h), (258, 3, 3, 8 + len(pixels)), (259, 3, 1, 1), (262, 3, 1, 2),
            (273, 4, 1, 8), (277, 3, 1, 3), (278, 3, 1, h), (279, 4, 1, len(pixels)), (284, 3, 1, 1),
            (339, 3, 3, 8 + len(pixels) + 6)]
    ifd = 8 + len(pixels) + 12
    body = struct.pack("<2sHI", b"II", 42, ifd) + pixels + struct.pack("<3H", 32, 32, 32) + struct.pack("<3H", 3, 3, 3)
    body += struct.pack("<H", len(tags)) + b"".join(
        struct.pack("<HHI", t, k, n) + (struct.pack("<HH", v, 0) if k == 3 and n == 1 else struct.pack("<I", v))
        for t, k, n, v in tags) + struct.pack("<I", 0)
    path.write_bytes(body)


def test_a_float_colour_tiff_is_refused_saying_to_save_it_as_exr(tmp_path):
    p = tmp_path / "render.tif"
    _float_rgb_tiff(p)
    with pytest.raises(ImageError, match="not an image file this reader knows; a TIFF of float colours is read as "
                                         r"\.exr: save it as one") as exc:
        decode(str(p))
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("name, mode, frames", [
    ("photo.gif", "P", 1), ("animation.gif", "P", 2), ("pages.tif", "RGB", 2), ("photo.bmp", "RGB", 1),
    ("photo.tga", "RGB", 1), ("photo.ppm", "RGB", 1), ("photo.webp", "RGB", 1), ("print.jpg", "CMYK", 1),
    ("print.tif", "CMYK", 1), ("lab.tif", "LAB", 1), ("palette.png", "P", 1), ("bits.png", "1", 1),
])
def test_every_pillow_format_reads_as_its_first_frame_in_rgb(tmp_path, name, mode, frames):
    """A GIF, a CMYK print file, a LAB TIFF, a palette or 1-bit PNG: the first frame's colours as Pillow converts
    them to RGB (a multi-page TIFF or an animated GIF is read by its first frame, as Blender reads one), three
    channels, with no alpha where the file has no transparency."""
    rng = np.random.default_rng(3)
    first = Image.fromarray((rng.random((24, 20, 3)) * 255).astype(np.uint8)).convert(mode)
    later = [Image.fromarray((rng.random((24, 20, 3)) * 255).astype(np.uint8)).convert(mode)
             for _ in range(frames - 1)]
    path = tmp_path / name
    first.save(path, save_all=frames > 1, append_images=later, **({"lossless": True} if name.endswith(".webp") else {}))
    with Image.open(path) as im:
        want = np.asarray(im.convert("RGB"), dtype=np.float32) / 255
    got = decode(str(path))
    assert got.shape == (24, 20, 3)
    np.testing.assert_allclose(got, want, atol=1e-6)
    assert read_rgb(str(path)).shape == (24, 20, 3)


def _exr(path, chans):
    import OpenEXR
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, chans) as f:
        f.write(str(path))


def test_an_exr_is_read_by_its_picture_and_one_of_several_layers_is_refused(tmp_path):
    """RGB, RGBA, Y or a sole channel is the picture (a depth channel beside RGB is left); an EXR of an alpha and a
    render layer's colours, or of R and G alone, names no picture: it is refused naming its channels (the alpha
    was read as the picture, all white)."""
    rng = np.random.default_rng(4)
    plane = lambda: rng.random((8, 6)).astype(np.float32)    # noqa: E731
    rgb = rng.random((8, 6, 3)).astype(np.float32)
    _exr(tmp_path / "beauty.exr", {"RGB": rgb, "Z": plane() * 100})
    np.testing.assert_array_equal(decode(str(tmp_path / "beauty.exr")), rgb)
    mask = plane()
    _exr(tmp_path / "mask.exr", {"mask": mask})
    np.testing.assert_array_equal(decode(str(tmp_path / "mask.exr"))[..., 0], mask)
    _exr(tmp_path / "layers.exr", {"diffuse.R": plane(), "diffuse.G": plane(), "diffuse.B": plane(),
                                   "A": np.ones((8, 6), np.float32)})
    _exr(tmp_path / "rg.exr", {"R": plane(), "G": plane()})
    for name, names in (("layers.exr", "A, diffuse"), ("rg.exr", "G, R")):
        with pytest.raises(ImageError, match=f"{name}: an EXR image must hold RGB, RGBA, Y or one channel, not "
                                             f"{names}; save") as exc:
            decode(str(tmp_path / name))
        assert "\n" not in str(exc.value)


def test_an_exr_of_several_parts_is_refused_naming_them(tmp_path):
    """A compositor's multi-part EXR (one pass a part) was read by its first part, whichever pass that was: refused
    naming the parts, as an EXR of several layers is; an EXR of one named part reads as before."""
    import OpenEXR
    rng = np.random.default_rng(5)

    def part(name, pixels):
        return OpenEXR.Part({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, "name": name},
                            {"RGB": pixels}, name)

    depth, beauty = (rng.random((8, 6, 3)).astype(np.float32) for _ in range(2))
    with OpenEXR.File([part("depth", depth), part("beauty", beauty)]) as f:
        f.write(str(tmp_path / "passes.exr"))
    with pytest.raises(ImageError, match=r"passes\.exr: an EXR image must be one part, not 2 \(depth, beauty\); "
                                         "save the picture's part as an EXR of its own") as exc:
        decode(str(tmp_path / "passes.exr"))
    assert "\n" not in str(exc.value)
    with OpenEXR.File([part("beauty", beauty)]) as f:
        f.write(str(tmp_path / "one.exr"))
    np.testing.assert_array_equal(decode(str(tmp_path / "one.exr")), beauty)


def test_writing_a_large_png_holds_no_float_copies_of_it(tmp_path):
    """A ramp's colours written as an 8-bit PNG: encoding and compressing take a few MiB beside the image and its
    bytes, whatever its size (the whole-image float temporaries took 87 bytes a pixel at 4096^2, four times what a
    bake is allowed for), and give the pixels IEC 61966-2-1's formula gives, block boundaries included."""
    import tracemalloc

    from omninoise.export.images import encode_srgb8, write_png

    n = 1024
    y, x = np.mgrid[0:n, 0:n].astype(np.float32) / n
    rgba = np.stack([x, y, x * y, 1.0 - x], axis=-1) * np.float32(1.2) - np.float32(0.1)   # past both ends too
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        encoded = encode_srgb8(rgba)
        write_png(str(tmp_path / "ramp.png"), encoded)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    assert peak < encoded.nbytes + 16 * 2 ** 20, peak / 2 ** 20                # the input is 16 MiB, 4 MiB out
    c = np.clip(rgba.astype(np.float64), 0.0, 1.0)
    c[..., :3] = np.where(c[..., :3] <= 0.0031308, 12.92 * c[..., :3], 1.055 * c[..., :3] ** (1 / 2.4) - 0.055)
    assert np.abs(encoded.astype(int) - np.floor(c * 255 + 0.5)).max() <= 1    # float32 rounding at half steps
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "ramp.png")), encoded)
