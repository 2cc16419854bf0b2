"""Fretting damage indicators: Ruiz's FDP and FFDP, and the surface tangential stress they need.

Ruiz, Boddington and Chen (Exp. Mech. 1984) correlate fretting damage with the product of the
frictional shear τ and the slip amplitude δ, FDP = τ·δ (wear and surface damage), and
fretting-fatigue crack initiation with FFDP = σ_t·τ·δ, where σ_t is the tangential (in-plane)
stress at the surface in the direction of slip; Nowell and Hills (Wear 1990) discuss both.
Only tension opens a crack, so FFDP takes σ_t where it is tensile and 0 where it compresses.

The surface stress is recovered from the condensed surface displacements, which are exact at
the surface nodes: the in-plane strain of every surface facet (from its nodes' displacements),
averaged to the nodes, and the contact pressure as the normal stress σ_nn = −p. Linear isotropic
elasticity with σ_nn given eliminates the normal strain:

    σ_dd = E/(1 − ν²)·[(1 − ν)·ε_dd + ν·tr ε_s] + ν/(1 − ν)·σ_nn        (3D)
    σ_tt = E/(1 − ν²)·ε_tt + ν/(1 − ν)·σ_nn                             (plane strain)

with ε_s the surface strain tensor, d the unit tangent direction, tr ε_s its in-plane trace (in
plane strain the out-of-plane strain is 0, and the 3D form reduces to the 2D one).

Pure functions of arrays, vectorised over points and facets. Units: mm, MPa; FDP in MPa·mm
(= N/mm = mJ/mm²), FFDP in MPa²·mm.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def surface_strain(coordinates: np.ndarray, facets: np.ndarray, displacement: np.ndarray) -> np.ndarray:
    """In-plane strain tensor of a surface at its nodes, (n, dim, dim), in global axes.

    coordinates, displacement: (n, dim) mm; facets: (m, k) node indices (lines in 2D,
    triangles or quadrilaterals in 3D). Per facet, the surface gradient of u is taken at its
    centre (a line's or a triangle's exact gradient, a quadrilateral's bilinear map at ξ = η = 0),
    projected onto the facet's tangent plane and symmetrised; each node averages the facets
    around it weighted by their size. The tensor has no normal components (ε·n = 0).
    """
    n, dim = coordinates.shape
    return (surface_strain_operator(coordinates, facets) @ displacement.ravel()).reshape(n, dim, dim)


def surface_strain_operator(coordinates: np.ndarray, facets: np.ndarray) -> sp.csr_matrix:
    """The linear map of :func:`surface_strain`, sparse (n·dim·dim, n·dim): the strain of
    nodal displacements u (n, dim) mm is ``(S @ u.ravel()).reshape(n, dim, dim)``."""
    n, dim = coordinates.shape
    k = facets.shape[1]
    x = coordinates[facets]  # (m, k, dim)
    if k == 4:  # the bilinear map's derivatives at the centre
        derivative = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) / 4  # (k, 2)
    else:  # lines and triangles: edges from the first node
        derivative = np.vstack([-np.ones((1, k - 1)), np.eye(k - 1)])  # (k, k-1)
    J = np.einsum("mkd,ka->mda", x, derivative)  # (m, dim, k-1)
    metric = np.swapaxes(J, 1, 2) @ J  # (m, k-1, k-1)
    pseudo_inverse = np.linalg.inv(metric) @ np.swapaxes(J, 1, 2)  # (m, k-1, dim): tangent coordinates
    projector = J @ pseudo_inverse  # onto the facet's tangent plane, (m, dim, dim)
    size = np.sqrt(np.linalg.det(metric))
    weight = np.zeros(n)
    for corner in range(k):
        np.add.at(weight, facets[:, corner], size)
    weight = np.maximum(weight, np.finfo(float).tiny)
    # ∇_s u of a unit displacement of corner c along axis d is e_d ⊗ (derivative[c]·pseudo_inverse);
    # projected onto the tangent plane and symmetrised, it is the facet's strain of that unit motion
    rows, cols, vals = [], [], []
    pair = np.arange(dim * dim).reshape(dim, dim)
    for c in range(k):
        row_of_c = np.einsum("a,mad->md", derivative[c], pseudo_inverse)  # (m, dim)
        for d in range(dim):
            in_plane = projector[:, :, d, None] * row_of_c[:, None, :]  # P·(e_d ⊗ g), (m, dim, dim)
            strain = 0.5 * (in_plane + np.swapaxes(in_plane, 1, 2))
            for corner in range(k):  # averaged to every node of the facet, by size
                node = facets[:, corner]
                share = (size / weight[node])[:, None, None] * strain
                rows.append((node[:, None, None] * dim * dim + pair[None]).ravel())
                cols.append(np.repeat(facets[:, c] * dim + d, dim * dim))
                vals.append(share.ravel())
    operator = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(n * dim * dim, n * dim))
    operator.sum_duplicates()
    return operator


def tangential_stress(strain: np.ndarray, direction: np.ndarray, pressure: np.ndarray,
                      young: float, poisson: float) -> np.ndarray:
    """Surface stress σ_dd (n,) MPa along the unit tangents ``direction`` (n, dim).

    strain: (n, dim, dim) surface strain (:func:`surface_strain`); pressure: p (n,) MPa, the
    normal stress being −p; young: E MPa; poisson: ν. See the module for the relation.
    """
    along = np.einsum("ni,nij,nj->n", direction, strain, direction)
    trace = np.trace(strain, axis1=1, axis2=2)
    dim = strain.shape[1]
    # plane strain (dim 2): the in-plane trace is ε_tt itself and the 3D form reduces to E'·ε_tt
    in_plane = (1.0 - poisson) * along + poisson * trace if dim == 3 else along
    return young / (1.0 - poisson ** 2) * in_plane - poisson / (1.0 - poisson) * pressure


def slip_direction(shear: np.ndarray, tangents: np.ndarray) -> np.ndarray:
    """Unit direction (n, dim) of the shear traction in global axes.

    shear: τ (n, dim-1) MPa in each point's tangent frame; tangents: (n, dim-1, dim). Points
    without shear take their first tangent (σ_t there multiplies a zero FDP).
    """
    vector = np.einsum("nk,nkd->nd", shear, tangents)
    norm = np.linalg.norm(vector, axis=1, keepdims=True)
    return np.where(norm > 0.0, vector / np.where(norm > 0.0, norm, 1.0), tangents[:, 0])


def fretting_damage(max_shear: np.ndarray, slip_range: np.ndarray,
                    tangential: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ruiz's FDP = τ·δ (MPa·mm) and FFDP = ⟨σ_t⟩·τ·δ (MPa²·mm) of every point in a cycle.

    max_shear: the largest |τ| (MPa) in the cycle; slip_range: the range of the irreversible
    slip path over the cycle (mm), so δ = slip_range/2 is the slip amplitude; tangential: the
    most tensile σ_t (MPa) in the cycle; ⟨σ_t⟩ = max(σ_t, 0).
    """
    fdp = max_shear * 0.5 * slip_range
    return fdp, np.maximum(tangential, 0.0) * fdp


def field_maximum(values: np.ndarray, coordinates: np.ndarray) -> tuple[float, list[float]]:
    """The largest value of a per-point field and where it is (mm); the first such point."""
    at = int(np.argmax(values))
    return float(values[at]), [float(c) for c in coordinates[at]]


class DamageTracker:
    """The most tensile surface stress σ_t of each point over a load cycle.

    ``record(displacement, pressure, shear)`` after every increment (the slave surface's
    displacements (n, dim) mm, pressure (n,) MPa, shear (n, dim-1) MPa) keeps the largest
    σ_t along the current shear direction; :meth:`cycle` returns FDP, FFDP and σ_t for the
    cycle's τ_max and slip range and starts the next cycle. No I/O.
    """

    def __init__(self, coordinates, facets, tangents, young: float, poisson: float):
        self.coordinates, self.facets, self.tangents = coordinates, facets, tangents
        self._strain = surface_strain_operator(coordinates, facets)
        self.young, self.poisson = young, poisson
        self.largest = np.full(len(coordinates), -np.inf)

    def record(self, displacement: np.ndarray, pressure: np.ndarray, shear: np.ndarray) -> np.ndarray:
        strain = (self._strain @ displacement.ravel()).reshape(len(self.coordinates), *displacement.shape[1:] * 2)
        sigma = tangential_stress(strain, slip_direction(shear, self.tangents), pressure,
                                  self.young, self.poisson)
        self.largest = np.maximum(self.largest, sigma)
        return sigma

    def cycle(self, max_shear: np.ndarray, slip_range: np.ndarray) -> dict:
        tangential = np.where(np.isfinite(self.largest), self.largest, 0.0)
        fdp, ffdp = fretting_damage(max_shear, slip_range, tangential)
        self.largest = np.full(len(self.coordinates), -np.inf)
        return {"fdp": fdp, "ffdp": ffdp, "surface_tangential_stress": tangential}

    def figures(self, fields: dict) -> dict:
        """Maxima and their locations (mm) of FDP and FFDP, and the most tensile σ_t."""
        out = {}
        for name, key in (("fdp", "fdp_max_MPa_mm"), ("ffdp", "ffdp_max_MPa2_mm"),
                          ("surface_tangential_stress", "surface_tangential_stress_max_MPa")):
            out[key], out[key.split("_max")[0] + "_max_location_mm"] = field_maximum(fields[name], self.coordinates)
        return out


__all__ = [
    "DamageTracker",
    "field_maximum",
    "fretting_damage",
    "slip_direction",
    "surface_strain",
    "tangential_stress",
]
