"""Cutting coefficients of work materials for the mechanistic milling force (tangential,
radial and axial; cutting in N/mm^2 and edge in N/mm), each with its source, the cutter and
the lubrication it was identified with.

Every entry is from Table 5 of the review "Milling force model for aviation aluminum alloy:
academic insight and perspective analysis", Chinese Journal of Mechanical Engineering 34 (2021)
98, doi:10.1186/s10033-021-00536-9, with the reference number it cites.  The table prints the
edge coefficients' unit as "N·mm"; they are per length of edge, N/mm, as the model's units
require and as their values (7.5 to 27.7 for aluminium) show.  Values for one alloy differ
about 2x between sources (Al7075-T6: K_tc 767 [190], 600 [160]): the cutter, its geometry and
the conditions differ, so keep the source with the entry.  Where a source gives no axial
coefficients the entry's are 0: no axial force.

No steel, titanium or plastic yet: no source with all six coefficients has been checked here;
a user gives their own: ``coefficients = { K_tc = ..., ... }`` on a ``[tool]``, ``[[tools]]``
entry or ``end_milling`` disturbance, over its ``material``'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CuttingCoefficients:
    """Mechanistic cutting (N/mm^2) and edge (N/mm) force coefficients."""

    K_tc: float
    K_rc: float
    K_ac: float
    K_te: float
    K_re: float
    K_ae: float

    def as_array(self) -> np.ndarray:
        """``[K_tc, K_rc, K_ac, K_te, K_re, K_ae]``, the order the kernels take."""
        return np.array([self.K_tc, self.K_rc, self.K_ac, self.K_te, self.K_re, self.K_ae])


@dataclass(frozen=True)
class Material:
    """A work material's coefficients and where they come from."""

    coefficients: CuttingCoefficients
    alloy: str
    cutter: str
    lubrication: str
    source: str


_REVIEW = "Chinese J. Mech. Eng. 34 (2021) 98, Table 5"

#: Al7075-T6, carbide, dry: the twin's default.
ALUMINIUM_7075_T6 = CuttingCoefficients(K_tc=767.01, K_rc=168.8, K_ac=222.0, K_te=27.7, K_re=26.6, K_ae=0.7)

#: The materials by name (``material = ...`` on a tool or an end-milling disturbance).
MATERIALS: dict[str, Material] = {
    "aluminium_7075_t6": Material(ALUMINIUM_7075_T6, "Al7075-T6", "cemented carbide", "dry", f"{_REVIEW}, ref. [190]"),
    "aluminium_7075_t6_ref160": Material(
        CuttingCoefficients(K_tc=600.46, K_rc=180.96, K_ac=0.0, K_te=17.9, K_re=20.42, K_ae=0.0),
        "Al7075-T6",
        "cemented carbide",
        "dry",
        f"{_REVIEW}, ref. [160] (no axial coefficients given)",
    ),
    "aluminium_7075_hss": Material(
        CuttingCoefficients(K_tc=951.365, K_rc=262.597, K_ac=323.33, K_te=11.115, K_re=11.314, K_ae=1.105),
        "Al7075",
        "high-speed steel",
        "dry",
        f"{_REVIEW}, ref. [156]",
    ),
    "aluminium_6061_t6": Material(
        CuttingCoefficients(K_tc=243.77, K_rc=113.5, K_ac=0.0, K_te=7.53, K_re=7.83, K_ae=0.0),
        "Al6061-T6",
        "cemented carbide",
        "dry",
        f"{_REVIEW}, ref. [160] (no axial coefficients given)",
    ),
    "aluminium_6082_t6": Material(
        CuttingCoefficients(K_tc=631.0, K_rc=99.0, K_ac=273.0, K_te=13.0, K_re=10.0, K_ae=2.8),
        "Al6082-T6",
        "cemented carbide",
        "dry",
        f"{_REVIEW}, ref. [189]",
    ),
    "aluminium_almgsi05_mql": Material(
        CuttingCoefficients(K_tc=561.2, K_rc=194.4, K_ac=6.7, K_te=204.3, K_re=16.2, K_ae=2.2),
        "AlMgSi0.5",
        "cemented carbide",
        "minimum quantity lubrication",
        f"{_REVIEW}, ref. [150]",
    ),
}
