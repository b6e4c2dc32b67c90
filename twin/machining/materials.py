"""Cutting coefficients of work materials for the milling force (tangential, radial and axial),
each with its source, the cutter and the lubrication it was identified with.  Two forms:

Linear (mechanistic)
    ``F_t = K_tc b h + K_te b`` and the like (cutting coefficients in N/mm^2, edge in N/mm).  Every
    aluminium entry is from Table 5 of the review "Milling force model for aviation aluminum
    alloy: academic insight and perspective analysis", Chinese Journal of Mechanical Engineering
    34 (2021) 98, doi:10.1186/s10033-021-00536-9, with the reference number it cites.  The table
    prints the edge coefficients' unit as "N·mm"; they are per length of edge, N/mm, as the
    model's units require and as their values (7.5 to 27.7 for aluminium) show.  Values for one
    alloy differ about 2x between sources (Al7075-T6: K_tc 767 [190], 600 [160]): the cutter, its
    geometry and the conditions differ, so keep the source with the entry.  Where a source gives
    no axial coefficients the entry's are 0: no axial force.
Kienzle
    ``F_t = kc1 b h^(1 - mc)``: the specific cutting force ``kc = kc1 h^-mc`` (h in mm; kc1 the
    value at h = 1 mm, N/mm^2), the form of the tool makers' power formulas.  It is held as a
    :class:`CuttingCoefficients` with ``mc > 0``: ``K_tc = kc1`` and ``K_rc``, ``K_ac`` the
    radial and axial forces' values at h = 1 mm, no edge coefficients (the exponent carries the
    size effect instead).  The force kernels linearise it about the mean chip thickness of the
    engaged arc at each step (:func:`twin.machining.cutting.kienzle_coefficients`).

    Where the source gives kc at several feeds, kc1 and mc are a least-squares fit in log-log
    (:func:`fit_kienzle`), done here from the source's numbers (:data:`MITSUBISHI_MILLING_KC`),
    with its largest relative residual kept on the entry.  Sources:

    * Mitsubishi Materials, technical information, "Cutting Power for Face Milling"
      (mitsubishicarbide.com .../tec_rotating_tools/.../tec_milling_power_formula), the "Kc"
      table: specific cutting force Kc (MPa) of each work material at a feed per tooth of 0.1,
      0.2, 0.3, 0.4 and 0.6 mm/tooth, for the page's power formula
      ``Pc = ap ae vf Kc / (60e6 eta)``.  The page names no cutter geometry, grade, speed or
      coolant for the table (its worked example: a 250 mm face mill, 12 inserts, 80 m/min).  The
      table's abscissa is the feed per tooth; the fit takes it as the chip thickness h (ours: the
      page does not say at which chip thickness, and a face mill's lead angle and immersion make
      the mean chip thinner than fz).  Fitted over 0.1 to 0.6 mm; kc1 (at 1 mm) is an
      extrapolation of the fit, a parameter rather than a value the page gives.
    * ISCAR, "Material groups according to DIN/ISO 513 and VDI 3323" table (Kc1 in N/mm^2 "for 1
      mm^2 chip cross section", and mc, per material group), in the ISCAR boring systems
      catalogue 2022, "ISO materials and grades user guide", p. 111 of the catalogue as
      docs.steelcam.org shows it (iscar/katalog-iscar-rastochnye-sistemy-2022-page111): group 37,
      titanium alpha+beta alloys, hardened, 1050 N/mm^2: Kc1 1245, mc 0.24.  The same table in
      ISCAR's 2017 turning catalogue (katalog-tokarnyj-instrument-2017-page558) gives group 37 as
      Kc1 2110, mc 0.22: 1.7x more; we take the newer edition.  No tool or conditions are given
      (a turning/boring catalogue's general values).

    Radial and axial: no source checked here gives them for these materials, so they are a
    ratio of ours, :data:`KIENZLE_RADIAL_RATIO` and :data:`KIENZLE_AXIAL_RATIO` of the
    tangential force, the same exponent: round numbers near the middle of the aluminium
    entries' K_rc/K_tc (0.16 to 0.47) and K_ac/K_tc (0.01 to 0.43).

Sandvik Coromant's specific cutting force page (kc1 and mc by material group, the law
``kc = kc1 h^-mc``) was found, but the text stored for it here holds no kc1 or mc values (they
are in an image), so none is used.  No plastic or wood yet.  A user gives their own:
``coefficients = { K_tc = ..., ... }`` (linear) or ``{ kc1_N_per_mm2 = ..., mc = ... }``
(Kienzle) on a ``[tool]``, ``[[tools]]`` entry or ``end_milling`` disturbance, over its
``material``'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controllers.registries import Registry


@dataclass(frozen=True)
class CuttingCoefficients:
    """Cutting (N/mm^2) and edge (N/mm) force coefficients, and the Kienzle exponent ``mc``.

    ``mc = 0``: the linear mechanistic model.  ``mc > 0``: the Kienzle form, the cutting
    coefficients the forces per chip area at h = 1 mm (``K_tc = kc1``), each times ``h^-mc``."""

    K_tc: float
    K_rc: float
    K_ac: float
    K_te: float
    K_re: float
    K_ae: float
    mc: float = 0.0

    def as_array(self) -> np.ndarray:
        """``[K_tc, K_rc, K_ac, K_te, K_re, K_ae, mc]``, the order the kernels take."""
        return np.array([self.K_tc, self.K_rc, self.K_ac, self.K_te, self.K_re, self.K_ae, self.mc])

    @property
    def model(self) -> str:
        """``"linear"`` or ``"Kienzle"``."""
        return "Kienzle" if self.mc else "linear"


#: The radial and axial forces of a Kienzle entry, fractions of the tangential (ours: no source
#: checked gives them for these materials; see the module docstring).
KIENZLE_RADIAL_RATIO = 0.3
KIENZLE_AXIAL_RATIO = 0.3


def kienzle(kc1_N_per_mm2: float, mc: float) -> CuttingCoefficients:
    """The Kienzle form ``kc = kc1 h^-mc`` as coefficients: radial and axial from
    :data:`KIENZLE_RADIAL_RATIO` and :data:`KIENZLE_AXIAL_RATIO`, no edge coefficients."""
    return CuttingCoefficients(
        K_tc=kc1_N_per_mm2,
        K_rc=KIENZLE_RADIAL_RATIO * kc1_N_per_mm2,
        K_ac=KIENZLE_AXIAL_RATIO * kc1_N_per_mm2,
        K_te=0.0,
        K_re=0.0,
        K_ae=0.0,
        mc=mc,
    )


@dataclass(frozen=True)
class KienzleFit:
    """kc1 (N/mm^2) and mc fitted to a source's kc at several chip thicknesses, and the fit's
    largest relative deviation from the source's values."""

    kc1_N_per_mm2: float
    mc: float
    max_relative_residual: float


def fit_kienzle(h_mm, kc_N_per_mm2) -> KienzleFit:
    """Least squares of ``log kc = log kc1 - mc log h`` over the given points (h in mm)."""
    h, kc = np.asarray(h_mm, float), np.asarray(kc_N_per_mm2, float)
    slope, intercept = np.polyfit(np.log(h), np.log(kc), 1)
    kc1, mc = float(np.exp(intercept)), float(-slope)
    residual = float(np.max(np.abs(kc1 * h**-mc / kc - 1.0)))
    return KienzleFit(kc1, mc, residual)


@dataclass(frozen=True)
class Material:
    """A work material's coefficients and where they come from (``fit``: the Kienzle fit the
    coefficients are, where they are fitted)."""

    coefficients: CuttingCoefficients
    alloy: str
    cutter: str
    lubrication: str
    source: str
    fit: KienzleFit | None = None

    @property
    def model(self) -> str:
        """``"linear"``, ``"Kienzle"`` or ``"Kienzle (fit)"``."""
        return self.coefficients.model + (" (fit)" if self.fit else "")


_REVIEW = "Chinese J. Mech. Eng. 34 (2021) 98, Table 5"
_MITSUBISHI = (
    'Mitsubishi Materials, "Cutting Power for Face Milling", Kc table at fz 0.1-0.6 mm/tooth '
    "(face milling; no cutter, speed or coolant stated)"
)
_ISCAR = (
    'ISCAR boring catalogue 2022 p. 111, "Material groups (ISO 513, VDI 3323)", group 37 (turning/boring '
    "general values; no tool or conditions stated; the 2017 turning catalogue gives Kc1 2110, mc 0.22)"
)

#: The feeds per tooth (mm) of Mitsubishi's Kc table.
MITSUBISHI_FEEDS_MM = (0.1, 0.2, 0.3, 0.4, 0.6)
#: Rows of Mitsubishi's "Cutting Power for Face Milling" Kc table (MPa = N/mm^2) at
#: :data:`MITSUBISHI_FEEDS_MM`: the page's work material and its tensile strength or hardness.
MITSUBISHI_MILLING_KC: dict[str, tuple[float, ...]] = {
    "Mild Steel 520 MPa": (2200, 1950, 1820, 1700, 1580),
    "Medium Steel 620 MPa": (1980, 1800, 1730, 1600, 1570),
    "Chrome Molybdenum Steel 730 MPa": (2540, 2250, 2140, 2000, 1800),
    "Austenitic Stainless Steel 155 HB": (2030, 1970, 1900, 1770, 1710),
    "Grey Cast Iron 200 HB": (1750, 1400, 1240, 1050, 970),
    "Brass 500 MPa": (1150, 950, 800, 700, 630),
}


def _mitsubishi(row: str, alloy: str) -> Material:
    """An entry fitted to a row of :data:`MITSUBISHI_MILLING_KC`."""
    fit = fit_kienzle(MITSUBISHI_FEEDS_MM, MITSUBISHI_MILLING_KC[row])
    source = f"{_MITSUBISHI}, row {row!r}: kc1, mc our log-log fit, largest residual {fit.max_relative_residual:.1%}"
    return Material(kienzle(fit.kc1_N_per_mm2, fit.mc), alloy, "face mill, inserts", "not stated", source, fit)


#: Al7075-T6, carbide, dry: the twin's default.
ALUMINIUM_7075_T6 = CuttingCoefficients(K_tc=767.01, K_rc=168.8, K_ac=222.0, K_te=27.7, K_re=26.6, K_ae=0.7)

_LIBRARY: dict[str, Material] = {
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
    "steel_mild_520": _mitsubishi("Mild Steel 520 MPa", "plain carbon (mild) steel, 520 MPa"),
    "steel_medium_620": _mitsubishi("Medium Steel 620 MPa", "plain carbon (medium) steel, 620 MPa"),
    "steel_cr_mo_730": _mitsubishi("Chrome Molybdenum Steel 730 MPa", "Cr-Mo alloy steel, 730 MPa"),
    "stainless_austenitic": _mitsubishi("Austenitic Stainless Steel 155 HB", "austenitic stainless steel, 155 HB"),
    "cast_iron_grey": _mitsubishi("Grey Cast Iron 200 HB", "grey cast iron, 200 HB"),
    "brass": _mitsubishi("Brass 500 MPa", "brass, 500 MPa"),
    "titanium_alpha_beta": Material(
        kienzle(1245.0, 0.24),
        "titanium alpha+beta alloy (as Ti-6Al-4V), hardened, 1050 MPa",
        "catalogue value, no tool stated",
        "not stated",
        _ISCAR,
    ),
}


def _registry(library: dict[str, Material]) -> Registry[Material]:
    """The ``library`` as a registry: each entry's summary its model, alloy, cutter and
    lubrication."""
    registry: Registry[Material] = Registry("material")
    for name, material in library.items():
        registry.add(
            name, material, summary=f"{material.model}: {material.alloy}, {material.cutter}, {material.lubrication}"
        )
    return registry


#: The materials by name (``material = ...`` on a tool or an end-milling disturbance): each
#: entry's value is the :class:`Material` (its coefficients and their source).
MATERIALS = _registry(_LIBRARY)

#: The material of a tool or an end-milling disturbance that names none.
DEFAULT_MATERIAL = "aluminium_7075_t6"
