"""Wear laws: what the wear gap gains in an increment from the contact pressure and the slip.

:class:`Archard` is the paper's equation 5. The bookkeeping of the per-increment columns (forces, energies,
widths, state counts) is the kernel :func:`dolfinx_fretting.wear.commit_increment`; the law supplies its
coefficients.
"""

from __future__ import annotations

from dataclasses import dataclass

from .settings import finite

__all__ = ["Archard"]


@dataclass(frozen=True)
class Archard:
    """Archard's wear law, the paper's equation 5: the wear gap grows by ``k p |dx_t|`` where contacts slide.

    Give ``k`` (1/MPa with N, mm), or for two deformable bodies ``k_slave`` and ``k_master``: both see the
    same pressure and slip, the wear gap grows with their sum and each body wears its share.
    ``acceleration`` multiplies k in cycles (each simulated cycle stands for that many physical ones).
    """

    k: float | None = None
    k_slave: float | None = None
    k_master: float | None = None
    acceleration: float = 1.0

    def __post_init__(self) -> None:
        per_body = (self.k_slave is not None, self.k_master is not None)
        if any(per_body) and not all(per_body):
            raise ValueError("Archard: give both k_slave and k_master, or k alone")
        if any(per_body) and self.k is not None:
            raise ValueError("Archard: give either k or (k_slave, k_master), not both")
        if not any(per_body) and self.k is None:
            raise ValueError("Archard: k (1/MPa, finite, >= 0) is required")
        for name in ("k", "k_slave", "k_master"):
            if getattr(self, name) is not None:
                finite(f"Archard.{name}", getattr(self, name), 0.0)
        finite("Archard.acceleration", self.acceleration, 1.0)

    @property
    def k_total(self) -> float:
        """The wear gap's coefficient, ``k`` or ``k_slave + k_master``."""
        return float(self.k) if self.k is not None else float(self.k_slave + self.k_master)

    @property
    def slave_share(self) -> float:
        """Fraction of the wear gap worn from the slave body (1 with a single ``k``)."""
        if self.k is not None or self.k_total == 0:
            return 1.0
        return float(self.k_slave) / self.k_total

    def coefficient(self, in_cycle: bool) -> float:
        """The coefficient applied to an increment: :attr:`k_total`, times ``acceleration`` in a load cycle (each
        simulated cycle stands for that many physical ones)."""
        return self.k_total * (self.acceleration if in_cycle else 1.0)
