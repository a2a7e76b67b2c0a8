"""Collision checking of the robot against itself, the table and the floor (coal).

Two precisions share one code path: convex hulls (fast, conservative: a hull contains
its mesh, so hull distances never exceed mesh distances; tested) for sampling and planning, and
the original meshes for the independent re-check of ``posegen check``.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from posegen.robot.bounds import BoundingSpheres
from posegen.robot.collision_geometry import add_self_pairs, carrying_links, link_of, robot_geometry
from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene

TABLE = "table"
FLOOR = "floor"
FLOOR_SIZE_M = 20.0
FLOOR_THICKNESS_M = 0.1
_DEFAULT_GJK_GUESS = (1.0, 0.0, 0.0)  # coal's defaults: what a fresh GeometryData starts from
_DEFAULT_SUPPORT_GUESS = (0, 0)
NEAR_M = 0.02  # pairs within this of a check's margin by their bound are sorted first; the rest only if reached


class _Screen:
    """A geometry workspace for exact distances from coal's default guesses, and its active pairs.

    coal writes each query's final guesses back into the pair's request (a warm start for
    the next query); they are set back to the defaults before every query, so an answer
    depends on the placement alone. They are written in place, through views of the
    requests' own vectors made once: assigning new vectors cost 2.6 us a query, more
    than the 1.7 us of a typical TALOS query itself.

    The workspace remembers the configuration it is placed at and, once asked, its pairs'
    bounds: a pool's sample checked and then separated asks both twice at one posture.
    """

    def __init__(self, data: pin.GeometryData) -> None:
        self.data = data
        self.active = np.array(data.activeCollisionPairs, dtype=bool)  # (pairs,)
        self._guesses = [(r.cached_gjk_guess, r.cached_support_func_guess) for r in data.distanceRequests]
        self.placed: FloatArray | None = None  # (nq,) the configuration the geometry is placed at
        self.bounds: FloatArray | None = None  # (pairs,) m, read-only: its pairs' lower bounds, once computed

    def distance(self, geom: pin.GeometryModel, k: int) -> coal.DistanceResult:
        """Pair ``k``'s exact distance from coal's default guesses (an answer of the placement alone)."""
        guess, support = self._guesses[k]  # views of the request's vectors: (3,) and (2,)
        guess[0], guess[1], guess[2] = _DEFAULT_GJK_GUESS
        support[0], support[1] = _DEFAULT_SUPPORT_GUESS
        return pin.computeDistance(geom, self.data, k)


@dataclass(frozen=True)
class Proximity:
    """The closest pair of bodies in a configuration."""

    distance_m: float  # negative when penetrating
    pair: tuple[str, str]


@dataclass(frozen=True)
class Collision(Proximity):
    """A pair closer than its margin."""

    margin_m: float  # the pair's margin (:meth:`CollisionChecker.pair_margins`)

    @property
    def excess_m(self) -> float:
        """How far inside its margin the pair is (m, positive)."""
        return self.margin_m - self.distance_m


@dataclass(frozen=True)
class Witness:
    """One collision pair's nearest points in a configuration (world frame)."""

    pair: int  # index in the geometry model's collision pairs
    distance_m: float  # negative when penetrating
    points_m: tuple[FloatArray, FloatArray]  # (3,) each: the nearest point on the pair's first and second body
    normal: FloatArray  # (3,) unit, from the first body toward the second
    joints: tuple[int, int]  # the pinocchio joints carrying the first and second body (0: the world)


class CollisionChecker:
    """Self, table and floor collisions of a scene's robot.

    The soles' links may touch the floor; the links carrying a chain's contact points
    (fingertips, point frame) and its declared ``touching_links`` may touch the table when
    that chain is in contact (``contact_chain``), never otherwise.
    """

    def __init__(self, scene: Scene, convex: bool = True) -> None:
        self.scene = scene
        model = scene.model
        geom = robot_geometry(model, scene.urdf_xml, scene.files.package_dirs, scene.config.collision, convex)
        n_robot = len(geom.geometryObjects)
        add_self_pairs(model, geom, scene.files.srdf_path(), scene.config.collision)

        size = scene.table.size_m
        table_placement = pin.SE3(scene.table_pose) * pin.SE3(np.eye(3), np.array([0.0, 0.0, -size[2] / 2]))
        floor_placement = pin.SE3(np.eye(3), np.array([0.0, 0.0, -FLOOR_THICKNESS_M / 2]))
        obstacles = {
            TABLE: (coal.Box(*size), table_placement),
            FLOOR: (coal.Box(FLOOR_SIZE_M, FLOOR_SIZE_M, FLOOR_THICKNESS_M), floor_placement),
        }
        frame_of = link_of(model, geom)
        floor_ok = set(scene.stance.floor_contact_frames)
        for name, (shape, placement) in obstacles.items():
            obj = pin.GeometryObject(name, 0, 0, placement, shape)
            index = geom.addGeometryObject(obj)
            for i in range(n_robot):
                if name == FLOOR and frame_of[i] in floor_ok:
                    continue
                geom.addCollisionPair(pin.CollisionPair(i, index))
        self.geom = geom
        self._names = [str(o.name) for o in geom.geometryObjects]
        table_index = self._names.index(TABLE)
        self._table_pairs = np.array([table_index in (p.first, p.second) for p in geom.collisionPairs], dtype=bool)
        self._exempt: dict[str | None, list[int]] = {None: []}
        for chain in scene.chains:
            touching = tuple(frame for kind in chain.kinds for frame in kind.carried_frames(chain))
            tips = carrying_links(model, touching, set(frame_of)) | set(chain.touching_links)
            self._exempt[chain.name] = [
                k
                for k, p in enumerate(geom.collisionPairs)
                if table_index in (p.first, p.second) and frame_of[min(p.first, p.second)] in tips
            ]
        self._model_data = model.createData()
        self._fast: dict[str | None, tuple[pin.GeometryData, NDArray[np.bool_]]] = {}
        self._fast_margin: dict[str | None, tuple[float, float | None]] = {}
        self._screen: dict[str | None, _Screen] = {}
        self._bounds: BoundingSpheres | None = None

    def _fresh_data(self, contact_chain: str | None) -> pin.GeometryData:
        # coal's solvers warm-start from earlier queries; fresh data (~1.5 ms) makes every
        # answer depend on this configuration only, whatever was checked before it.
        data = pin.GeometryData(self.geom)
        for k in self._exempt[contact_chain]:
            data.deactivateCollisionPair(k)
        return data

    @property
    def n_pairs(self) -> int:
        """Number of collision pairs checked (before contact exemptions)."""
        return len(self.geom.collisionPairs)

    def _pair_names(self, k: int) -> tuple[str, str]:
        pair = self.geom.collisionPairs[k]
        return self._names[pair.first], self._names[pair.second]

    def closest(self, q: FloatArray, contact_chain: str | None) -> Proximity:
        """Smallest distance over the active pairs.

        Args:
            q: Full configuration, shape (nq,).
            contact_chain: The chain whose fingertips touch the table, or None.

        """
        data = self._fresh_data(contact_chain)
        pin.computeDistances(self.scene.model, self._model_data, self.geom, data, q)
        active = np.array(data.activeCollisionPairs, dtype=bool)
        distances = np.array([r.min_distance for r in data.distanceResults])
        distances[~active] = np.inf
        k = int(np.argmin(distances))
        return Proximity(distance_m=float(distances[k]), pair=self._pair_names(k))

    def closest_unless_within(self, q: FloatArray, contact_chain: str | None, margin_m: float) -> Proximity | None:
        """The closest pair, or None as soon as some pair is found closer than ``margin_m``.

        The answer of :meth:`closest` (the same pair and distance, bit for bit) when no pair
        is within the margin, at a fraction of its cost: pairs are visited by increasing
        bounding-sphere bound (:mod:`posegen.robot.bounds`), and the exact distance runs
        only while a bound is below the best distance found. Each exact query starts from
        coal's default guesses, so the answer depends on ``q`` alone.

        Args:
            q: Full configuration, shape (nq,).
            contact_chain: The chain whose fingertips touch the table, or None.
            margin_m: Stop at the first pair closer than this (m).

        """
        screen, bounds = self._screened(q, contact_chain)
        best, best_pair = np.inf, -1
        for k in _by_bound(bounds, margin_m + NEAR_M):
            if bounds[k] >= best:
                break
            distance = float(screen.distance(self.geom, k).min_distance)
            if distance < margin_m:
                return None
            if distance < best:
                best, best_pair = distance, k
        return Proximity(distance_m=best, pair=self._pair_names(best_pair))

    def _spheres(self) -> BoundingSpheres:
        """The bounding spheres of the geometry (made on first use)."""
        if self._bounds is None:
            self._bounds = BoundingSpheres(self.geom)
        return self._bounds

    def _fast_workspace(self, contact_chain: str | None) -> tuple[pin.GeometryData, NDArray[np.bool_]]:
        """:meth:`collides`' geometry data for ``contact_chain`` (warm-started) and its active pairs (made once)."""
        if contact_chain not in self._fast:
            data = self._fresh_data(contact_chain)
            self._fast[contact_chain] = (data, np.array(data.activeCollisionPairs, dtype=bool))
        return self._fast[contact_chain]

    def _screening(self, contact_chain: str | None, q: FloatArray) -> _Screen:
        """The screening workspace of ``contact_chain`` (made on first use), placed at ``q``."""
        if contact_chain not in self._screen:
            self._screen[contact_chain] = _Screen(self._fresh_data(contact_chain))
        screen = self._screen[contact_chain]
        if screen.placed is None or not np.array_equal(q, screen.placed):
            pin.updateGeometryPlacements(self.scene.model, self._model_data, self.geom, screen.data, q)
            screen.placed, screen.bounds = np.array(q, dtype=float), None
        return screen

    def _screened(self, q: FloatArray, contact_chain: str | None) -> tuple[_Screen, FloatArray]:
        """The screening workspace placed at ``q``, and every pair's lower bound (m; inf: inactive)."""
        screen = self._screening(contact_chain, q)
        if screen.bounds is None:
            bounds = self._spheres().lower_bounds(screen.data)
            bounds[~screen.active] = np.inf
            bounds.flags.writeable = False
            screen.bounds = bounds
        return screen, screen.bounds

    def witnesses(
        self, q: FloatArray, contact_chain: str | None, within_m: float, pairs: Sequence[int] | None = None
    ) -> list[Witness]:
        """The active pairs closer than ``within_m`` and their nearest points, by pair index.

        Args:
            q: Full configuration, shape (nq,).
            contact_chain: The chain whose fingertips touch the table, or None.
            within_m: Distance below which a pair is returned (m).
            pairs: Only these pairs (indices of active pairs, e.g. an earlier answer's),
                without screening the others; None: every active pair.

        Example:
            >>> near = checker.witnesses(q, "left", 0.01)  # pairs within 1 cm, e.g. the two thighs

        """
        if pairs is None:
            screen, bounds = self._screened(q, contact_chain)
            candidates = np.flatnonzero(bounds < within_m).tolist()
        else:
            screen = self._screening(contact_chain, q)
            candidates = list(pairs)
        found = []
        for k in candidates:
            result = screen.distance(self.geom, k)
            if result.min_distance < within_m:
                pair = self.geom.collisionPairs[k]
                objects = self.geom.geometryObjects[pair.first], self.geom.geometryObjects[pair.second]
                points = np.array(result.getNearestPoint1()), np.array(result.getNearestPoint2())
                normal = np.array(result.normal, dtype=float)
                found.append(
                    Witness(
                        k, float(result.min_distance), points, normal, (objects[0].parentJoint, objects[1].parentJoint)
                    )
                )
        return found

    def pair_margins(self, margin_m: float, table_margin_m: float | None = None) -> FloatArray:
        """Each collision pair's margin (m): ``margin_m``, or the larger ``table_margin_m`` for the table's pairs.

        Example:
            >>> margins = checker.pair_margins(0.005, 0.03)  # (n_pairs,) m: 0.03 for a hand and the table

        """
        margins = np.full(len(self._table_pairs), margin_m)
        if table_margin_m is not None:
            margins[self._table_pairs] = max(margin_m, table_margin_m)
        return margins

    def collides(
        self, q: FloatArray, contact_chain: str | None, margin_m: float, table_margin_m: float | None = None
    ) -> bool:
        """Whether any active pair is closer than its margin (a fast yes/no for planning).

        Only the pairs whose bounding-sphere bound (:mod:`posegen.robot.bounds`) is below
        their margin are asked of coal; the others cannot be closer. Reuses one
        GeometryData per contact chain: coal's warm starts could only change a verdict
        for a pair within numerical precision (1e-15 m) of the margin.

        Args:
            q: Full configuration, shape (nq,).
            contact_chain: The chain whose fingertips touch the table, or None.
            margin_m: Every pair's margin (m).
            table_margin_m: A larger margin for the pairs of the robot and the table (m), or None.

        """
        data, active = self._fast_workspace(contact_chain)
        margins = self.pair_margins(margin_m, table_margin_m)  # (n_pairs,) m
        if self._fast_margin.get(contact_chain) != (margin_m, table_margin_m):
            for request, margin in zip(data.collisionRequests, margins.tolist(), strict=True):
                request.security_margin = margin
            self._fast_margin[contact_chain] = (margin_m, table_margin_m)
        pin.updateGeometryPlacements(self.scene.model, self._model_data, self.geom, data, q)
        bounds = self._spheres().lower_bounds(data)
        for k in np.flatnonzero((bounds < margins) & active).tolist():
            if pin.computeCollision(self.geom, data, k):
                return True
        return False

    def colliding_pairs(
        self, q: FloatArray, contact_chain: str | None, margin_m: float, table_margin_m: float | None = None
    ) -> list[Collision]:
        """Pairs closer than their margin (coal collision queries with a security margin).

        Args:
            q: Full configuration, shape (nq,).
            contact_chain: The chain whose fingertips touch the table, or None.
            margin_m: Security margin (m).
            table_margin_m: A larger margin for the pairs of the robot and the table (m), or None.

        Returns:
            The offending pairs with their distance and margin, closest first; empty if none.

        """
        data = self._fresh_data(contact_chain)
        margins = self.pair_margins(margin_m, table_margin_m).tolist()  # (n_pairs,) m
        for request, margin in zip(data.collisionRequests, margins, strict=True):
            request.security_margin = margin
        pin.computeCollisions(self.scene.model, self._model_data, self.geom, data, q, False)
        hits = [k for k, r in enumerate(data.collisionResults) if r.isCollision() and data.activeCollisionPairs[k]]
        if not hits:
            return []
        pin.updateGeometryPlacements(self.scene.model, self._model_data, self.geom, data)
        found = []
        for k in hits:
            result = pin.computeDistance(self.geom, data, k)
            found.append(Collision(float(result.min_distance), self._pair_names(k), margins[k]))
        return sorted(found, key=lambda p: p.distance_m)


def _by_bound(bounds: FloatArray, split_m: float) -> Iterator[int]:
    """Pair indices by increasing bound, ties by index (a stable sort), those below ``split_m`` sorted first.

    The pairs at or above ``split_m`` are sorted only when the caller gets that far: a
    check stops at the first bound above its best distance, nearly always below the
    split (a stable argsort of TALOS's 989 pairs costs 33 us, that of the few near ones 10 us).
    """
    near = bounds < split_m
    for group in (np.flatnonzero(near), np.flatnonzero(~near)):
        yield from group[np.argsort(bounds[group], kind="stable")].tolist()
