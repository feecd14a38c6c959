"""The obstacle shapes by name: one registry entry per shape.

An obstacle is an :class:`~dolfinx_fretting.contact.Obstacle` (its frame, its candidate search, what moves with
it); a new shape is one class in its own module and one line here. The names are those a run's description
(``run.json``'s ``obstacle.kind``) and the pictures use.
"""

from __future__ import annotations

from .contact import ElasticBody, Obstacle, RigidPlane

__all__ = ["OBSTACLES", "obstacle_kind"]

#: Every obstacle shape, by name.
OBSTACLES: dict[str, type[Obstacle]] = {"rigid_plane": RigidPlane, "elastic_body": ElasticBody}


def obstacle_kind(obstacle: Obstacle) -> str:
    """The registry name of ``obstacle``'s shape (its class or the closest registered base class)."""
    for cls in type(obstacle).__mro__:
        for name, shape in OBSTACLES.items():
            if shape is cls:
                return name
    raise ValueError(f"obstacle_kind: {type(obstacle).__name__} is not a registered shape "
                     f"({', '.join(OBSTACLES)}): add it to dolfinx_fretting.obstacles.OBSTACLES")
