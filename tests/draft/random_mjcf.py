"""Random MJCF robots for the conversion's tests against MuJoCo's own reading.

A free root body and a tree of bodies below it, each placed by a random orientation form
(``quat``, ``euler`` with any ``eulerseq``, ``axisangle``, ``xyaxes``, ``zaxis``) and holding
0-2 joints (hinges and slides, with or without ``pos``, ``axis``, ``ref``) and 1-3 geoms
(spheres, boxes, cylinders, capsules, some visual only); nested default classes give joint
and geom attributes through ``class`` and ``childclass``; the compiler's angles are in
degrees or radians. Names: bodies ``b<k>``, joints ``j<k>_<i>``, geoms ``g<k>_<i>``.
"""

from __future__ import annotations

import numpy as np

SHAPES = {"sphere": 1, "box": 3, "cylinder": 2, "capsule": 2}  # type -> number of sizes
INERTIAL = '<inertial pos="0.01 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>'


def _numbers(rng: np.random.Generator, n: int, low: float, high: float) -> str:
    return " ".join(f"{v:.6g}" for v in rng.uniform(low, high, n))


class RandomMjcf:
    """One random model; :meth:`text` writes it."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        self.degree = bool(self.rng.random() < 0.5)
        self.classes: list[str] = []
        self.bodies = 0

    def text(self) -> str:
        rng = self.rng
        sequence = "".join(rng.permutation(list("xyz" if rng.random() < 0.5 else "XyZ")))
        compiler = f'<compiler angle="{"degree" if self.degree else "radian"}" eulerseq="{sequence}"/>'
        main = '<joint armature="0.01"/><geom type="box" size="0.05 0.05 0.05"/>'  # two equal hinges: not singular
        defaults = f"<default>{main}{self._class('c', 0)}</default>"
        root = f'<body name="root" pos="0 0 1"><freejoint/>{INERTIAL}<geom type="sphere" size="0.05"/>'
        root += "".join(self._body(1) for _ in range(2)) + "</body>"
        return f'<mujoco model="random">{compiler}{defaults}<worldbody>{root}</worldbody></mujoco>'

    def _angle(self, rad: float) -> float:
        return float(np.degrees(rad)) if self.degree else rad

    def _orientation(self) -> str:
        rng = self.rng
        form = int(rng.integers(6))
        turn = self._angle(float(rng.uniform(-np.pi, np.pi)))
        return [
            "",
            f' quat="{_numbers(rng, 4, -1, 1)}"',
            f' euler="{" ".join(f"{self._angle(a):.6g}" for a in rng.uniform(-1.5, 1.5, 3))}"',
            f' axisangle="{_numbers(rng, 3, -1, 1)} {turn:.6g}"',
            f' xyaxes="{_numbers(rng, 6, -1, 1)}"',
            f' zaxis="{_numbers(rng, 3, -1, 1)}"',
        ][form]

    def _class(self, name: str, level: int) -> str:
        rng = self.rng
        self.classes.append(name)
        joint = []
        if rng.random() < 0.5:
            joint.append(f'axis="{_numbers(rng, 3, -1, 1)}"')
        if rng.random() < 0.5:
            joint.append(f'ref="{self._angle(float(rng.uniform(-1, 1))):.6g}"')
        if rng.random() < 0.4:
            joint.append(f'pos="{_numbers(rng, 3, -0.05, 0.05)}"')
        geom = self._geom_attributes(typed=rng.random() < 0.5)
        inner = f"<joint {' '.join(joint)}/><geom {geom}/>"
        children = "".join(self._class(f"{name}_{k}", level + 1) for k in range(int(rng.integers(0, 3)) * (level < 2)))
        return f'<default class="{name}">{inner}{children}</default>'

    def _geom_attributes(self, typed: bool) -> str:
        rng = self.rng
        attributes = []
        if typed:
            kind = str(rng.choice(list(SHAPES)))
            attributes += [f'type="{kind}"', f'size="{_numbers(rng, SHAPES[kind], 0.02, 0.1)}"']
        if rng.random() < 0.4:
            attributes.append(f'pos="{_numbers(rng, 3, -0.1, 0.1)}"')
        if rng.random() < 0.3:
            attributes.append(f'contype="{rng.integers(0, 2)}" conaffinity="{rng.integers(0, 2)}"')
        if rng.random() < 0.3:
            attributes.append(f'quat="{_numbers(rng, 4, -1, 1)}"')
        return " ".join(attributes)

    def _joint(self, name: str) -> str:
        rng = self.rng
        slide = rng.random() < 0.15
        attributes = f' name="{name}"' + (' type="slide"' if slide else "")
        if rng.random() < 0.7:
            attributes += f' axis="{_numbers(rng, 3, -1, 1)}"'
        if rng.random() < 0.4:
            attributes += f' pos="{_numbers(rng, 3, -0.05, 0.05)}"'
        if rng.random() < 0.4:
            ref = rng.uniform(-0.3, 0.3) if slide else self._angle(float(rng.uniform(-1, 1)))
            attributes += f' ref="{ref:.6g}"'
        if rng.random() < 0.3:
            attributes += f' class="{rng.choice(self.classes)}"'
        low, high = rng.uniform(-1, -0.1), rng.uniform(0.1, 1)
        if not slide:
            low, high = self._angle(low), self._angle(high)
        return f'<joint{attributes} range="{low:.6g} {high:.6g}"/>'

    def _body(self, depth: int) -> str:
        rng = self.rng
        self.bodies += 1
        k = self.bodies
        childclass = f' childclass="{rng.choice(self.classes)}"' if rng.random() < 0.3 else ""
        text = f'<body name="b{k}" pos="{_numbers(rng, 3, -0.3, 0.3)}"{self._orientation()}{childclass}>{INERTIAL}'
        text += "".join(self._joint(f"j{k}_{i}") for i in range(int(rng.integers(0, 3)) if depth > 1 else 1))
        for i in range(int(rng.integers(1, 4))):
            own = f' class="{rng.choice(self.classes)}"' if rng.random() < 0.4 else ""
            text += f'<geom name="g{k}_{i}"{own} {self._geom_attributes(typed=rng.random() < 0.6)}/>'
        if depth < 4:
            text += "".join(self._body(depth + 1) for _ in range(int(rng.integers(0 if depth > 1 else 1, 3))))
        return text + "</body>"
