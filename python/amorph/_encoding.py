"""Fixed-length encodings of genomes, for optimizers that search a box of real numbers."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ._amorph import Genome, Scene


def unit_genome(scene: Scene, x: Sequence[float]) -> Genome:
    """The genome of ``x``: N points × 6 numbers in [0, 1] (values outside are clipped), each
    point's x, y, z, density, falloff and material, scaled into ``scene``'s limits. The material
    is the palette's ``floor(u · materials)``.

    CMA-ES, a GA or any optimizer over the unit box can then design for Amorph:
    ``cluster.evaluate([unit_genome(scene, x) for x in batch])``.
    """
    u = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    if u.ndim != 1 or u.size == 0 or u.size % 6:
        raise ValueError(f"unit_genome: expected N × 6 numbers, got shape {u.shape}")
    u = u.reshape(-1, 6)
    limits = scene.limits
    materials = len(scene.materials)
    (d0, d1), (f0, f1) = limits["density"], limits["falloff"]
    points = np.empty_like(u)
    points[:, 0:3] = u[:, 0:3]
    points[:, 3] = d0 + u[:, 3] * (d1 - d0)
    points[:, 4] = f0 + u[:, 4] * (f1 - f0)
    points[:, 5] = np.minimum(np.floor(u[:, 5] * materials), materials - 1)
    return Genome(points)
