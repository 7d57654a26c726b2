import io
import json

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from stipple.cli import main


def run(args, **kwargs):
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


@pytest.fixture
def map_path(tmp_path):
    latitude = np.linspace(90, -90, 18)[:, None] + np.zeros(36)
    path = tmp_path / "north.npy"
    np.save(path, latitude)  # high values (many dots) in the north
    return path


def test_sphere_outputs(map_path, tmp_path):
    names = ["dots.csv", "dots.geojson", "dots.svg", "globe.png"]
    outputs = [item for name in names for item in ("-o", tmp_path / name)]
    result = run(["sphere", map_path, "-M", 200, "-N", 16, "--iterations", 5, "-q"] + outputs)
    assert result.exit_code == 0, result.output
    table = np.loadtxt(tmp_path / "dots.csv", delimiter=",", skiprows=1)
    assert (tmp_path / "dots.csv").read_text().startswith("lon,lat\n") and table.shape == (200, 2)
    assert np.all(np.abs(table[:, 0]) <= 180) and np.all(np.abs(table[:, 1]) <= 90)
    assert np.sum(table[:, 1] > 0) > 2 * np.sum(table[:, 1] < 0)
    geojson = json.loads((tmp_path / "dots.geojson").read_text())
    coordinates = geojson["features"][0]["geometry"]["coordinates"]
    np.testing.assert_allclose(coordinates, table, atol=1e-6)
    svg = (tmp_path / "dots.svg").read_text()
    shown = svg.count("<circle")  # the visible side, tone-true round dots on the drawing
    assert 0 < shown < 200 and f"{shown} of 200 dots on the visible side" in svg
    assert Image.open(tmp_path / "globe.png").size == (1024, 1024)


def test_xyz_coordinates_and_equirect(map_path, tmp_path):
    result = run(
        [
            "sphere",
            map_path,
            "-M",
            50,
            "-N",
            8,
            "--iterations",
            2,
            "-q",
            "--coords",
            "xyz",
            "-o",
            "-",
            "-o",
            tmp_path / "map.png",
            "--projection",
            "equirect",
        ]
    )
    assert result.exit_code == 0, result.output
    table = np.loadtxt(result.stdout.splitlines()[1:], delimiter=",")
    np.testing.assert_allclose(np.linalg.norm(table, axis=1), 1, atol=1e-8)
    assert Image.open(tmp_path / "map.png").size == (1024, 512)


def test_uniform_and_builtins():
    result = run(["sphere", "--uniform", "-M", 30, "-N", 4, "--iterations", 3, "-q"])
    assert result.exit_code == 0 and len(result.stdout.splitlines()) == 31
    result = run(["sphere", "builtin:gaussians", "-M", 30, "-N", 6, "--iterations", 3, "-q"])
    assert result.exit_code == 0


@pytest.mark.parametrize(
    "args,message",
    [
        (["sphere", "builtin:nope"], "unknown built-in density"),
        (["sphere", "builtin:gaussians", "--invert"], "--invert transforms a map's or an image's values, not builtin"),
        (["sphere", "--uniform", "--gamma", 3, "--range", 0, 1], "--gamma, --range transform a map's or an image's"),
        (["sphere", "--uniform", "--invert", "--gamma", 3], "--gamma transforms a map's or an image's values, not"),
        (["sphere", "--uniform", "--kernel", "gauss"], "kernel must be"),
        (["sphere", "--uniform", "--view", "10"], "view must be LON,LAT"),
        (["sphere", "--uniform", "--projection", "equirect", "--view", "30,45"], "centred on a longitude only"),
        (["design", "-t", 4, "--projection", "equirect", "--view", "0,10"], "centred on a longitude only"),
        (["sphere", "--uniform", "-N", 0], "bandwidth (degree) must be an integer"),
    ],
)
def test_sphere_bad_options(args, message):
    result = run(args + ["-q"])
    assert result.exit_code == 1
    assert message in result.output


def test_uniform_with_invert_draws_white_dots_on_black(tmp_path):
    """--invert has no values to invert on the uniform sphere, but it still chooses the colours."""
    run(["sphere", "--uniform", "--invert", "-M", 50, "-N", 4, "--iterations", 2, "-q", "-o", tmp_path / "u.svg"])
    svg = (tmp_path / "u.svg").read_text()
    assert 'fill="#ffffff"' in svg and "#000000" in svg


def test_a_missing_map_or_input_is_bad_usage(tmp_path):
    """Exit code 2, as a missing IMAGE of ``stipple torus`` (docs/errors.md), for the sphere's MAP and for the
    INPUT that ``evaluate`` needs for a torus's or an ink layer's points."""
    result = run(["sphere", "-M", 10, "-q"])
    assert result.exit_code == 2 and "missing MAP" in result.output
    (tmp_path / "p.csv").write_text("x,y\n1,2\n3,4\n")
    (tmp_path / "l.csv").write_text("x,y,class\n1,2,c\n3,4,m\n")
    (tmp_path / "s.csv").write_text("lon,lat\n10,20\n30,-40\n")
    Image.new("L", (16, 16), 255).save(tmp_path / "d.png")
    for arguments in (["p.csv"], ["l.csv"], ["s.csv"], ["p.csv", "--line"], ["d.png"]):
        result = run(["evaluate", tmp_path / arguments[0], *arguments[1:]])
        assert result.exit_code == 2 and "missing INPUT" in result.output, arguments


def test_map_and_uniform_together_is_an_error(map_path):
    result = run(["sphere", map_path, "--uniform"])
    assert result.exit_code == 1 and "either MAP or --uniform" in result.output


def test_lon0_shifts_the_map(tmp_path):
    values = np.zeros((6, 12))
    values[:, 0] = 1.0  # first column only: [lon0, lon0 + 30°)
    np.save(tmp_path / "band.npy", values)
    result = run(["sphere", tmp_path / "band.npy", "-M", 100, "-N", 6, "--iterations", 0, "-q", "--lon0", "-180"])
    longitude = np.loadtxt(result.stdout.splitlines()[1:], delimiter=",")[:, 0]
    assert np.all((longitude >= 150) | (longitude <= -150))


def test_image_map_uses_dark_as_dense(tmp_path):
    picture = np.full((10, 20), 255, dtype=np.uint8)
    picture[:5] = 0
    Image.fromarray(picture).save(tmp_path / "dark-north.png")
    result = run(["sphere", tmp_path / "dark-north.png", "-M", 100, "-N", 6, "--iterations", 0, "-q"])
    latitude = np.loadtxt(result.stdout.splitlines()[1:], delimiter=",")[:, 1]
    assert np.all(latitude >= 0)


def test_init_from_lonlat_and_xyz_csv(tmp_path):
    start = tmp_path / "start.csv"
    run(["sphere", "--uniform", "-M", 40, "-N", 4, "--iterations", 0, "-q", "-o", start])
    same = run(["sphere", "--uniform", "-M", 40, "-N", 4, "--iterations", 0, "-q", "--init", start])
    expected = np.loadtxt(start, delimiter=",", skiprows=1)
    # Round-trip digits: back through unit vectors the degrees agree to the last bits of a double.
    np.testing.assert_allclose(np.loadtxt(io.StringIO(same.stdout), delimiter=",", skiprows=1), expected, atol=1e-12)
    xyz = tmp_path / "start-xyz.csv"
    run(["sphere", "--uniform", "-M", 40, "-N", 4, "--iterations", 0, "-q", "--coords", "xyz", "-o", xyz])
    again = run(["sphere", "--uniform", "-M", 40, "-N", 4, "--iterations", 0, "-q", "--init", xyz])
    np.testing.assert_allclose(np.loadtxt(io.StringIO(again.stdout), delimiter=",", skiprows=1), expected, atol=1e-12)


def test_map_from_stdin(map_path):
    result = run(["sphere", "-", "-M", 50, "-N", 6, "--iterations", 1, "-q"], input=map_path.read_bytes())
    assert result.exit_code == 0, result.output
    assert len(result.stdout.splitlines()) == 51


@pytest.mark.parametrize(("shape", "noted"), [((20, 40), False), ((20, 41), False), ((20, 60), True), ((20, 20), True)])
def test_a_map_that_is_not_two_to_one_gets_a_note(tmp_path, shape, noted):
    """An equirectangular map spans 360 by 180 degrees; another shape is read as one all the same (stretched)."""
    path = tmp_path / "map.npy"
    np.save(path, np.random.default_rng(0).random(shape) + 0.5)
    result = run(["sphere", str(path), "-M", "100", "--iterations", "2", "-o", str(tmp_path / "x.csv")])
    assert result.exit_code == 0, result.output
    assert ("not 2:1" in result.output) == noted, result.output


def test_the_equirect_picture_lies_over_its_map_and_follows_view(tmp_path):
    """The 2:1 map is drawn in the input's own layout (its first column at the left; it was drawn from lon -180,
    shifted half a turn against a map that starts at lon 0), and --view moves its centre (it was ignored)."""
    rows = 40
    darkness = np.full((rows, 2 * rows), 0.05)
    darkness[5:35, : rows // 2] = 0.9  # a dark block over lon 0..90 E (the map's first quarter)
    path = tmp_path / "block.npy"
    np.save(path, darkness)

    def quarters(*view):
        png = tmp_path / f"map{len(view)}.png"
        arguments = ["sphere", path, "-M", 1500, "--iterations", 20, "--projection", "equirect", "-q", "-o", png]
        assert run([*arguments, *view]).exit_code == 0
        gray = np.asarray(Image.open(png).convert("L"), dtype=float)
        return [1 - part.mean() / 255 for part in np.array_split(gray, 4, axis=1)]

    own = quarters()
    assert own[0] > 2 * max(own[1:]), own
    centred = quarters("--view", "0,0")  # lon 0 in the middle: the block in the third quarter
    assert centred[2] > 2 * max(centred[0], centred[1], centred[3]), centred


def test_uniform_points_are_mapped_around_lon_0_as_design_and_render_map_theirs(tmp_path):
    """Without a map file there is no layout to follow: --uniform's equirect map was centred on 180°."""
    csv, png = tmp_path / "u.csv", tmp_path / "u.png"
    arguments = ["--projection", "equirect", "--png-width", 720, "--dot-radius", "2px", "-q", "-o", csv, "-o", png]
    assert run(["sphere", "--uniform", "-M", 20, *arguments]).exit_code == 0
    lon, lat = np.loadtxt(csv, delimiter=",", skiprows=1).T
    gray = np.asarray(Image.open(png).convert("L"), dtype=float)
    rows, columns = gray.shape
    x = np.minimum(((lon + 180) % 360) / 360 * columns, columns - 1).astype(int)  # lon 0 in the middle
    y = np.minimum((90 - lat) / 180 * rows, rows - 1).astype(int)
    assert np.mean(gray[y, x] < 128) >= 0.75


def test_the_command_solves_with_single_precision_derivatives(map_path, tmp_path):
    """``stipple sphere`` asks for ``DERIVATIVE_EPSILON`` (the library's default is ``epsilon``): its points are
    the library's run with it, not without."""
    from stipple.sphere import halftone_sphere, lon_lat
    from stipple.torus import DERIVATIVE_EPSILON

    common = dict(threads=1, seed=3, iterations=8)
    run(["sphere", map_path, "-M", 300, "--threads", 1, "--seed", 3, "--iterations", 8, "-q", "-o", tmp_path / "a.csv"])
    drawn = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)
    single = lon_lat(halftone_sphere(str(map_path), 300, derivative_epsilon=DERIVATIVE_EPSILON, **common).points)
    double = lon_lat(halftone_sphere(str(map_path), 300, **common).points)
    np.testing.assert_allclose(drawn, np.column_stack(single), atol=1e-12)
    assert np.abs(drawn - np.column_stack(double)).max() > 1e-9


def test_a_pen_map_of_a_narrow_peak_is_clipped_and_solved(tmp_path):
    """A Gaussian of 4 degrees whose tails fall to 1e-300: the pen's clip level is near 1e-36, which the search
    did not reach (1399 of 1500 dots left out), and at that scale the run's single-precision derivatives
    underflowed (20 iterations, the dots in two clusters: a held-out review)."""
    latitude = np.radians(89.5 - np.arange(180))[:, None]
    longitude = np.radians(np.arange(360) + 0.5)[None, :]
    cosine = np.cos(latitude) * np.cos(longitude - np.pi)  # the peak at 0 N, 180 E
    angle = np.degrees(np.arccos(np.clip(cosine, -1, 1)))
    np.save(tmp_path / "peak.npy", np.exp(-0.5 * (angle / 4.0) ** 2))
    args = ["sphere", tmp_path / "peak.npy", "-M", 1500, "--dot-style", "point", "--pen-width", "0.5mm"]
    result = run([*args, "--width", "100mm", "--projection", "equirect", "-o", tmp_path / "a.csv"])
    assert result.exit_code == 0, result.output
    assert "left out" not in result.output and "energy settled" in result.output
    lon, lat = np.radians(np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)).T
    distance = np.degrees(np.arccos(np.clip(np.cos(lat) * np.cos(lon - np.pi), -1, 1)))
    assert 15 < np.percentile(distance, 90) < 90  # spread over a cap around the peak, none on the far side


@pytest.mark.parametrize("width, noted", [(2.0, True), (40.0, False)])
def test_a_narrow_peak_says_why_the_run_is_long(tmp_path, width, noted):
    """A 1-3 degree peak raised the degree many times over and ran for minutes, without a word (a held-out
    review)."""
    latitude = np.linspace(89, -89, 90)[:, None]
    longitude = np.linspace(-179, 179, 180)[None, :]
    path = tmp_path / "peak.npy"
    np.save(path, np.exp(-0.5 * (latitude**2 + longitude**2) / width**2) + 1e-4)
    result = run(["sphere", path, "-M", 2000, "--iterations", 1, "-o", tmp_path / "d.csv"])
    assert result.exit_code == 0, result.output
    assert ("the bandwidth rises from" in result.output) == noted, result.output


def test_the_equirect_map_wraps_at_its_left_and_right_edges(tmp_path):
    """Longitude wraps, but the map's radii were found as if its left and right edges were a frame: a flat 50 %
    gray map's first columns came out 204, 148, 96 for 128, a light line and a dark band (a held-out review)."""
    path = tmp_path / "gray.png"
    Image.new("L", (360, 180), 128).save(path)
    png = tmp_path / "map.png"
    arguments = ["sphere", path, "-M", 3000, "--iterations", 30, "--projection", "equirect", "-q", "--png-width", 1024]
    assert run([*arguments, "-o", png]).exit_code == 0
    gray = np.asarray(Image.open(png).convert("L"), dtype=float)[64:-64]  # away from the poles
    interior = gray[:, 20:-20].mean()
    edges = np.concatenate([gray[:, :3].mean(axis=0), gray[:, -3:].mean(axis=0)])
    assert np.abs(edges - interior).max() < 25, (edges, interior)


def test_a_blank_image_as_a_map_is_named(tmp_path):
    """An all-clear PNG said 'map: density is zero everywhere', not its file's name (a hostile review)."""
    from PIL import Image

    Image.new("RGBA", (36, 18), (0, 0, 0, 0)).save(tmp_path / "clear.png")
    result = CliRunner().invoke(
        main, ["sphere", str(tmp_path / "clear.png"), "-M", "20", "-q", "-o", str(tmp_path / "a.csv")]
    )
    assert result.exit_code == 1 and "clear.png: the image is blank (all white)" in result.output


@pytest.mark.parametrize(
    "arguments",
    [
        ["sphere", "--uniform", "-M", "60", "--iterations", "2", "-o", "{out}/x.csv", "--view", "10,10"],
        ["design", "-t", "4", "-o", "{out}/d.csv", "--projection", "equirect"],
        ["render", "{torus}", "-o", "{out}/r.png", "--view", "0,0"],
    ],
)
def test_view_and_projection_where_no_sphere_is_drawn_are_refused(tmp_path, arguments):
    """They were taken and ignored: CSV outputs only, or torus points (a fifth sweep)."""
    from click.testing import CliRunner

    from stipple.cli import main

    torus = tmp_path / "t.csv"
    torus.write_text("x,y\n1,2\n3,4\n")
    words = [word.format(out=tmp_path, torus=torus) for word in arguments]
    result = CliRunner().invoke(main, words)
    assert result.exit_code == 1
    assert "for a picture of the sphere (.png or .svg); here it would be ignored" in result.output
    assert not any(path.name in ("x.csv", "d.csv", "r.png") for path in tmp_path.iterdir())
