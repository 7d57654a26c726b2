"""Picture measures (stipple.measures.picture, ``stipple evaluate PICTURE.png INPUT``) against exact cases."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main
from stipple.io.images import load_density
from stipple.measures.picture import area_average, floyd_steinberg, measure_picture, on_grid

pytest.importorskip("skimage")


def ramp(rows=48, columns=64, low=0.1, high=0.8):
    return np.tile(np.linspace(low, high, columns), (rows, 1))


def colours(rows=40, columns=60, seed=0):
    smooth = np.random.default_rng(seed).random((rows // 10, columns // 10, 3))
    return np.asarray(Image.fromarray((smooth * 255).astype(np.uint8)).resize((columns, rows)), float) / 255


def lightness(gray):
    """CIE L* of an sRGB gray value (D65 white), from the sRGB and CIELAB definitions."""
    linear = gray / 12.92 if gray <= 0.04045 else ((gray + 0.055) / 1.055) ** 2.4
    f = np.cbrt(linear) if linear > (6 / 29) ** 3 else linear / (3 * (6 / 29) ** 2) + 4 / 29
    return 116 * f - 16


def test_a_picture_measured_against_itself_is_perfect():
    gray = measure_picture(ramp(), ramp())
    assert [m.sigma for m in gray] == [2.0, 4.0]
    assert all(m.rmse < 1e-12 and m.worst_tenth < 1e-12 for m in gray)
    colour = measure_picture(colours(), colours())
    assert all(m.delta_e00 < 1e-9 and m.chroma_ratio == pytest.approx(1) for m in colour)


def test_a_fine_checkerboard_is_its_mean_gray_from_afar_but_not_up_close():
    reference = np.full((64, 64), 0.5)
    checkerboard = np.indices((64, 64)).sum(axis=0) % 2.0
    far, near = measure_picture(reference, checkerboard, sigmas=(4.0, 0.3))
    assert far.rmse < 1e-3
    assert near.rmse > 0.2


def test_a_tone_shift_is_measured_as_that_shift_in_every_tenth():
    (measures,) = measure_picture(ramp(), ramp() + 0.05, sigmas=(3.0,))
    assert measures.rmse == pytest.approx(0.05)
    assert measures.mean_difference == pytest.approx(0.05)
    assert measures.worst_tenth == pytest.approx(0.05)
    assert [round(b.low, 1) for b in measures.tone_curve] == [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]
    assert all(b.output - b.input == pytest.approx(0.05) for b in measures.tone_curve)
    assert sum(b.pixels for b in measures.tone_curve) == ramp().size


def test_the_worst_tenth_is_a_tone_not_one_pixel():
    """A flat gray with one dark pixel drawn white: its own tenth (a pixel or two after the blur) is all error,
    but the worst tenth speaks of the tones that hold pixels, as the tone curve lists them."""
    reference = np.full((120, 160), 0.6)
    reference[60, 80] = 0.0
    drawn = reference.copy()
    drawn[60, 80] = 0.6
    (measures,) = measure_picture(reference, drawn, sigmas=(0.5,))
    assert max(abs(b.output - b.input) for b in measures.tone_curve) > 0.1
    assert measures.worst_tenth < 0.01
    (shifted,) = measure_picture(reference, drawn + 0.05, sigmas=(0.5,))
    assert shifted.worst_tenth == pytest.approx(0.05, abs=0.01)


def test_ciede2000_of_two_grays_is_their_lightness_difference_over_sl():
    """For neutral colours CIEDE2000 reduces to dL / S_L, S_L = 1 + 0.015 (L - 50)^2 / sqrt(20 + (L - 50)^2)."""
    a, b = 0.5, 0.6
    lab_a, lab_b = lightness(a), lightness(b)
    mean = (lab_a + lab_b) / 2
    sl = 1 + 0.015 * (mean - 50) ** 2 / np.sqrt(20 + (mean - 50) ** 2)
    (measures,) = measure_picture(np.full((20, 30, 3), a), np.full((20, 30, 3), b), sigmas=(2.0,))
    assert measures.delta_e00 == pytest.approx((lab_b - lab_a) / sl, rel=1e-6)
    assert measures.mean_L_difference == pytest.approx(lab_b - lab_a, rel=1e-6)
    assert measures.luminance_rmse == pytest.approx(0.1)


def test_a_gray_drawing_of_a_colour_input_has_no_chroma():
    reference = colours()
    (measures,) = measure_picture(reference, reference @ [0.299, 0.587, 0.114], sigmas=(2.0,))
    assert measures.chroma_ratio < 0.01
    assert measures.delta_e00 > 5


def test_a_picture_drawn_larger_and_inset_comes_back_onto_the_input_grid():
    reference = ramp(24, 32)
    big = np.kron(reference, np.ones((4, 4)))
    assert np.allclose(on_grid(big, reference.shape), reference, atol=1e-6)
    padded = np.pad(big, 8, constant_values=1.0)  # a 2-input-pixel margin on every side of a 32 x 24 input
    assert np.allclose(on_grid(padded, reference.shape, inset=2.0 * 32 / 36), reference, atol=1e-6)
    with pytest.raises(ValueError, match="inset"):
        on_grid(big, reference.shape, inset=12)


def test_floyd_steinberg_has_about_the_dots_asked_for_and_the_tone():
    reference = ramp(64, 96, 0.2, 0.9)
    picture, dots = floyd_steinberg(reference, 2000)
    assert abs(dots - 2000) < 0.03 * 2000
    assert measure_picture(reference, picture, sigmas=(4.0,))[0].rmse < 0.03
    colour, inked = floyd_steinberg(colours(60, 90), 1500)
    assert colour.shape == (60, 90, 3) and abs(inked - 1500) < 0.05 * 1500


def test_floyd_steinberg_of_white_dots_counts_the_white_pixels():
    """With ``--invert`` the dots are white on black: the baseline has about ``count`` white pixels, not black
    ones (a dark input's 8000 black pixels overstated its error three times), and keeps the tone."""
    reference = ramp(64, 96, 0.05, 0.5)  # mostly dark: white dots are the few
    picture, dots = floyd_steinberg(reference, 800, light_dots=True)
    negative, same = floyd_steinberg(1.0 - reference, 800)
    assert dots == same and abs(dots - 800) < 0.05 * 800
    np.testing.assert_allclose(picture, 1.0 - negative, atol=1e-12)
    assert measure_picture(reference, picture, sigmas=(4.0,))[0].rmse < 0.03
    black_dots, _ = floyd_steinberg(reference, 800)
    error = [measure_picture(reference, p, sigmas=(4.0,))[0].rmse for p in (picture, black_dots)]
    assert error[1] > 1.5 * error[0]


def test_area_average_is_exact_at_any_ratio(rng):
    """Floyd-Steinberg's dots come back onto the input's grid by exact areas (a nearest-neighbour 4x enlargement
    moved their edges by up to an eighth of a pixel): whole multiples, a split pixel by hand, the mean kept."""
    pixels = rng.random((7, 5))
    assert area_average(pixels, (14, 10)) == pytest.approx(np.repeat(np.repeat(pixels, 2, 0), 2, 1))
    assert area_average(np.repeat(np.repeat(pixels, 3, 0), 3, 1), (7, 5)) == pytest.approx(pixels)
    assert area_average(np.array([[0.0, 1.0]]), (1, 3)) == pytest.approx(np.array([[0.0, 0.5, 1.0]]))
    odd = rng.random((13, 17, 3))
    assert area_average(odd, (5, 4)).mean(axis=(0, 1)) == pytest.approx(odd.mean(axis=(0, 1)))


def test_bad_arguments_name_the_parameter():
    with pytest.raises(ValueError, match="sigmas"):
        measure_picture(ramp(), ramp(), sigmas=(0.0,))
    with pytest.raises(ValueError, match="picture"):
        measure_picture(ramp(), ramp() + 1)
    with pytest.raises(ValueError, match="count"):
        floyd_steinberg(ramp(), 0)


def save(path, values):
    Image.fromarray(np.round(np.asarray(values) * 255).astype(np.uint8)).save(path)
    return path


def evaluate(*args):
    return CliRunner().invoke(main, ["evaluate", *map(str, args)])


def test_evaluate_reports_a_pictures_measures_as_json(tmp_path):
    source = save(tmp_path / "in.png", ramp())
    big = save(tmp_path / "big.png", np.kron(ramp(), np.ones((3, 3))) - 0.04)
    result = evaluate(big, source, "--json", "-", "--sigma", "4", "--floyd-steinberg", "500")
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    assert report["measures"] == "gray" and report["drawn_shape"] == [144, 192]
    assert report["stipple"][0]["rmse"] == pytest.approx(0.04, abs=0.003)
    assert report["floyd_steinberg"]["dots"] > 0
    text = evaluate(big, source)
    assert text.exit_code == 0 and "sigma 2 px: luminance RMSE 0.04" in text.output


def test_evaluate_with_invert_measures_a_baseline_of_white_dots(tmp_path):
    """``--invert --floyd-steinberg M``: the baseline's M dots are white, as the picture's (it dithered M black
    ones, overstating its error on a dark input)."""
    source = save(tmp_path / "in.png", ramp(48, 72, 0.05, 0.4))
    report = json.loads(evaluate(source, source, "--invert", "--floyd-steinberg", "300", "--json", "-").output)
    reference = load_density(source, invert=True)  # the picture's light, white dots on black: w = u
    picture, dots = floyd_steinberg(reference, 300, light_dots=True)
    assert report["floyd_steinberg"]["dots"] == dots
    expected = measure_picture(reference, picture, sigmas=(2.0, 4.0))
    assert [m["rmse"] for m in report["floyd_steinberg"]["measures"]] == pytest.approx([m.rmse for m in expected])


def test_evaluate_measures_the_tone_the_run_was_asked_for(tmp_path):
    source = save(tmp_path / "in.png", ramp())
    for options, perfect in (([], True), (["--invert"], True), (["--gamma", "2"], False)):
        report = json.loads(evaluate(source, source, "--json", "-", *options).output)
        assert (report["stipple"][0]["rmse"] < 1e-9) == perfect


def test_evaluate_measures_colour_when_the_input_has_colour(tmp_path):
    source = save(tmp_path / "in.png", colours())
    report = json.loads(evaluate(source, source, "--json", "-").output)
    assert report["measures"] == "colour" and report["stipple"][0]["delta_e00"] < 1e-9
    assert json.loads(evaluate(source, source, "--json", "-", "--gray").output)["measures"] == "gray"


def test_a_neutral_input_gets_no_chroma_ratio(tmp_path):
    """A gray input's chroma is rounding noise: a CMY picture of it read "chroma 1255.673 of the input's"."""
    gray = np.repeat(ramp()[..., None], 3, axis=2)
    tinted = np.clip(gray + np.array([0.03, 0.0, -0.03]), 0, 1)
    source, picture = save(tmp_path / "in.png", gray), save(tmp_path / "tinted.png", tinted)
    report = evaluate(picture, source, "--colour")
    assert report.exit_code == 0, report.output
    assert "the input is neutral" in report.output and "of the input's" not in report.output
    rows = json.loads(evaluate(picture, source, "--colour", "--json", "-").output)["stipple"]
    assert all(row["chroma_ratio"] is None for row in rows) and all(row["delta_e00"] > 1 for row in rows)
    colour = save(tmp_path / "c.png", colours())
    coloured = json.loads(evaluate(colour, colour, "--json", "-").output)["stipple"]
    assert all(row["chroma_ratio"] == pytest.approx(1.0) for row in coloured)


@pytest.mark.parametrize("shape", [(20, 1000), (2, 500)])
def test_evaluate_measures_the_default_png_of_a_long_strip(tmp_path, shape):
    """Its height rounded to whole pixels puts its width : height 2.4 % off the input's: it was refused."""
    rows, columns = shape
    source = save(tmp_path / "in.png", ramp(rows, columns))
    result = CliRunner().invoke(main, ["torus", str(source), "-M", 300, "-q", "-o", str(tmp_path / "a.png")])
    assert result.exit_code == 0, result.output
    drawn = Image.open(tmp_path / "a.png")
    assert drawn.width == 1024 and abs(np.log((drawn.width / drawn.height) / (columns / rows))) > 0.02
    report = evaluate(tmp_path / "a.png", source, "--json", "-")
    assert report.exit_code == 0, report.output
    assert json.loads(report.output)["drawn_shape"] == [drawn.height, 1024]


@pytest.mark.parametrize("suffix", [".bmp", ".tif", ".gif", ".JPG"])
def test_a_picture_in_another_raster_format_measures_as_its_png(tmp_path, suffix):
    """A .bmp, .tif or .gif picture was read as a CSV of points ('expected a CSV with header x,y'); a JPEG's
    compression changes its measures a little."""
    source = save(tmp_path / "in.png", ramp())
    drawn = np.kron(ramp(), np.ones((3, 3))) - 0.04
    reports = [
        json.loads(evaluate(save(tmp_path / name, drawn), source, "--json", "-").output)
        for name in ("p.png", "p" + suffix)
    ]
    assert reports[1]["measures"] == "gray" and reports[1]["drawn_shape"] == [144, 192]
    tolerance = 0.002 if suffix == ".JPG" else 1e-9
    assert reports[1]["stipple"][0]["rmse"] == pytest.approx(reports[0]["stipple"][0]["rmse"], abs=tolerance)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda d: (d / "bad.png").write_bytes(b"not a png") and d / "bad.png", "cannot decode"),
        (lambda d: save(d / "wide.png", ramp(10, 64)), "not the same width : height"),
        (lambda d: save(d / "small.png", ramp(3, 2)), "not the same width : height"),  # a row off the rounding
        (lambda d: save(d / "globe.png", ramp(48, 48)), "draw the points with --projection equirect"),
    ],
)
def test_evaluate_refuses_a_bad_picture_in_one_line(tmp_path, make, message):
    """A square picture of a 2:1 map is a globe of stipple sphere: the line says how to measure it instead."""
    source = save(tmp_path / "in.png", ramp(48, 96))
    result = evaluate(make(tmp_path), source)
    assert result.exit_code == 1 and message in result.output
    assert len(result.output.strip().splitlines()) == 1


def test_a_picture_against_a_built_in_density_is_refused_in_one_line(tmp_path):
    """It said 'cannot read builtin:gaussians: No such file or directory' (a held-out review)."""
    picture = save(tmp_path / "p.png", ramp(32, 64))
    result = evaluate(picture, "builtin:gaussians")
    assert result.exit_code == 1 and "not a built-in density" in result.output
    assert len(result.output.strip().splitlines()) == 1
