"""Material laws. Linear isotropic elasticity now; J2 plasticity joins it later."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["LinearElastic"]


@dataclass(frozen=True)
class LinearElastic:
    """Isotropic linear elasticity (MPa). In 2D the formulation is plane strain.

    Args:
        E: Young's modulus (MPa), > 0.
        nu: Poisson's ratio, -1 < nu < 0.5.
    """

    E: float
    nu: float

    def __post_init__(self) -> None:
        if not self.E > 0:
            raise ValueError(f"material.E = {self.E} must be > 0 MPa")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"material.nu = {self.nu} must satisfy -1 < nu < 0.5")

    @property
    def lame(self) -> tuple[float, float]:
        """(lambda, mu) of the 3D law; with eps_zz = 0 it is also the plane-strain law."""
        lmbda = self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))
        return lmbda, self.E / (2 * (1 + self.nu))

    @property
    def plane_strain_modulus(self) -> float:
        """E / (1 - nu^2): the contact modulus E* against a rigid flat."""
        return self.E / (1 - self.nu**2)
