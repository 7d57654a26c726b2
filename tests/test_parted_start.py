"""A given start's dots at one place are parted before a run (``stipple.sampling.part_coincident``): each moved dot
lies at its sunflower distance from its place, every other dot stays bit for bit, and runs that could not part
them (the sphere's designs, maps without the near field) now end with every dot apart, as good as from their own
start; the manifolds' ``offset`` moves a point by the length asked in the direction asked."""

import numpy as np
import pytest

from stipple.halftone import run
from stipple.manifolds import Rectangle, Sphere, Torus
from stipple.sampling import PARTED_SPACING, golden_angles, part_coincident
from stipple.sphere import sphere_problem


def torus_distance(a, b, scale):
    delta = a - b
    delta -= np.rint(delta)
    return np.linalg.norm(delta * scale, axis=-1)


def sphere_distance(a, b):
    return np.arccos(np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0))


def test_torus_offset_moves_by_the_length_at_the_angle_in_the_scaled_metric():
    torus = Torus((2.0, 0.5))
    points = np.array([[0.1, 0.2], [0.95, 0.9]])
    lengths, angles = np.array([0.3, 0.05]), np.array([0.0, 2.0])
    moved = torus.offset(points, lengths, angles)
    assert np.allclose(torus_distance(moved, points, torus.scale), lengths)
    delta = moved - points
    delta -= np.rint(delta)
    assert np.allclose(np.arctan2(*(delta * torus.scale)[:, ::-1].T), angles)
    assert np.all((moved >= 0) & (moved < 1))


def test_sphere_offset_moves_along_a_great_circle_by_the_length():
    rng = np.random.default_rng(3)
    sphere = Sphere()
    points = np.vstack([sphere.random(rng, 50), np.eye(3), -np.eye(3)])
    lengths = rng.uniform(0.01, 2.5, len(points))
    moved = sphere.offset(points, lengths, rng.uniform(0, 2 * np.pi, len(points)))
    assert np.allclose(np.linalg.norm(moved, axis=1), 1.0)
    assert np.allclose(sphere_distance(moved, points), lengths)


def test_sphere_offsets_at_different_angles_go_different_ways():
    sphere = Sphere()
    place = np.repeat([[1.0, 0.0, 0.0]], 8, axis=0)
    angles = np.arange(8) * 2 * np.pi / 8
    moved = sphere.offset(place, np.full(8, 0.1), angles)
    chords = np.linalg.norm(moved[:, None] - moved[None], axis=-1)
    # Eight points evenly round a circle of radius sin(0.1): neighbours 2 sin(0.1) sin(pi / 8) apart.
    assert np.isclose(chords[~np.eye(8, dtype=bool)].min(), 2 * np.sin(0.1) * np.sin(np.pi / 8))


@pytest.mark.parametrize("manifold", [Torus((1.5, 1.0)), Sphere()], ids=["torus", "sphere"])
def test_repeated_points_are_parted_on_their_sunflower_and_the_others_stay(manifold):
    rng = np.random.default_rng(0)
    distinct = manifold.random(rng, 40)
    places = distinct[[3, 7]]
    points = np.vstack([distinct, np.repeat(places[:1], 9, axis=0), np.repeat(places[1:], 4, axis=0)])
    parted, moved = part_coincident(manifold, points)
    assert moved == 9 + 4  # the copies; each place keeps its first point (3 and 7)
    assert np.array_equal(parted[:40], points[:40])
    assert len(np.unique(parted, axis=0)) == len(points)
    spacing = np.sqrt(manifold.area / len(points))
    for place, moved in ((places[0], parted[40:49]), (places[1], parted[49:])):
        rank = np.arange(1, len(moved) + 1)
        here = np.repeat(place[None], len(moved), axis=0)
        distance = (
            torus_distance(moved, here, manifold.scale) if isinstance(manifold, Torus) else sphere_distance(moved, here)
        )
        assert np.allclose(distance, PARTED_SPACING * spacing * np.sqrt(rank))
    assert np.isclose(golden_angles(1), np.pi * (3 - np.sqrt(5)))


def test_points_without_repeats_come_back_as_they_are():
    torus = Torus()
    points = np.array([[0.5, 0.1], [0.5, 0.2], [0.1, 0.1]])  # a first coordinate repeats, no point does
    assert part_coincident(torus, points) == (points, 0)
    lone = np.random.default_rng(1).random((100, 2))
    assert part_coincident(torus, lone)[0] is lone


def test_the_rectangle_keeps_parted_points_inside():
    rectangle = Rectangle((1.0, 1.0), low=(0.2, 0.2), high=(0.8, 0.8))
    points = np.repeat([[0.5, 0.5]], 30, axis=0)
    parted, _ = part_coincident(rectangle, points)
    assert np.all((parted >= 0.2) & (parted <= 0.8))
    assert len(np.unique(parted, axis=0)) == 30


def test_a_design_from_one_place_ends_with_every_point_apart_and_as_good_as_its_own_start():
    # 300 dots at one place: every objective gives them the same gradient, and before the parting the run ended
    # with all 300 at one place.
    problem = sphere_problem(None, 300, kernel="distance", near_field=False)
    place = np.repeat([[0.3, -0.4, np.sqrt(0.75)]], 300, axis=0)
    parted = run(problem, init=place, correct=False)
    own = run(problem, init="uniform", correct=False)
    assert len(np.unique(parted.points, axis=0)) == 300
    # Stopped by tol relative to i.i.d. points' gradient, not the clumps' steep one (which stopped it early).
    assert parted.energy <= 1.005 * own.energy


def test_without_parting_a_start_at_one_place_stays_there():
    # What the parting is for: the plain run cannot separate them (the reason it exists).
    problem = sphere_problem(None, 50, kernel="distance", near_field=False)
    place = np.repeat([[0.0, 0.6, 0.8]], 50, axis=0)
    kept = run(problem, init=place, iterations=30, correct=False, part=False)
    assert len(np.unique(np.round(kept.points, 9), axis=0)) == 1
