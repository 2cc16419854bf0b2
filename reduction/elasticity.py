"""Linear-elastic finite-element bodies assembled with scikit-fem.

Units: mm, N, MPa (N/mm^2), t (tonne), s. Stiffness in N/mm, mass in t.
DOFs are node-interleaved: node k, component j sits at global index ``dim * k + j`` for
linear elements (scikit-fem's ``ElementVector`` ordering); ``ElasticBody.node_dofs`` is the
authoritative map and also covers the mid-edge nodes of quadratic tetrahedra.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import skfem
from skfem.helpers import ddot, dot, eye, sym_grad, trace
from skfem.models.elasticity import lame_parameters, plane_stress

from reduction.errors import InputError

_LINEAR_ELEMENTS = {
    skfem.MeshTri1: skfem.ElementTriP1,
    skfem.MeshQuad1: skfem.ElementQuad1,
    skfem.MeshTet1: skfem.ElementTetP1,
    skfem.MeshHex1: skfem.ElementHex1,
}
_QUADRATIC_ELEMENTS = {
    skfem.MeshTri1: skfem.ElementTriP2,
    skfem.MeshTet1: skfem.ElementTetP2,
    skfem.MeshTri2: skfem.ElementTriP2,
    skfem.MeshTet2: skfem.ElementTetP2,
    skfem.MeshHex1: skfem.ElementHexS2,  # 20-node serendipity hexahedra (Hex20 files)
}


@dataclass(frozen=True)
class ElasticBody:
    """An assembled linear-elastic body.

    stiffness: (n_dofs, n_dofs) CSR, N/mm. mass: CSR in t, or None when no density was given.
    node_dofs: (n_nodes, dim) int, global DOF of node k, component j. Nodes are the mesh
    vertices followed, for quadratic elements, by one node per mesh edge (mid-edge).
    basis: the DOF layout (``doflocs``, ``nodal_dofs``, ``N``); built by
    :func:`assemble_elastic_body` its quadrature data cover one element only (memory): to
    assemble a form, build a basis of the mesh.
    """

    mesh: skfem.Mesh
    basis: skfem.Basis
    dim: int
    stiffness: sp.csr_matrix
    mass: sp.csr_matrix | None
    node_dofs: np.ndarray

    @property
    def n_dofs(self) -> int:
        return int(self.stiffness.shape[0])

    @property
    def coordinates(self) -> np.ndarray:
        """(n_nodes, dim) node coordinates in mm, rows matching ``node_dofs``."""
        return self.basis.doflocs[:, self.node_dofs[:, 0]].T.copy()


def _element_for(mesh: skfem.Mesh, quadratic: bool) -> skfem.Element:
    table = _QUADRATIC_ELEMENTS if quadratic or isinstance(mesh, (skfem.MeshTri2, skfem.MeshTet2)) \
        else _LINEAR_ELEMENTS
    for mesh_type, element in table.items():
        if type(mesh) is mesh_type:
            return element()
    supported = sorted({t.__name__ for t in (*_LINEAR_ELEMENTS, *_QUADRATIC_ELEMENTS)})
    raise InputError(
        f"mesh type {type(mesh).__name__} (quadratic={quadratic}) is not supported for elasticity; "
        f"supported: {', '.join(supported)}"
    )


def _per_element(value, n_elements: int, name: str) -> np.ndarray:
    """Broadcast a scalar or per-element material value to shape (n_elements, 1)."""
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return np.full((n_elements, 1), float(array))
    if array.shape != (n_elements,):
        raise InputError(f"{name} must be a scalar or one value per element ({n_elements}), got shape {array.shape}")
    return array[:, None]


def _node_dofs(basis: skfem.Basis, dim: int) -> np.ndarray:
    blocks = [basis.nodal_dofs]
    if basis.edge_dofs.size:
        blocks.append(basis.edge_dofs)
    elif basis.facet_dofs.size and dim == 2:
        blocks.append(basis.facet_dofs)  # 2D quadratic: mid-edge nodes are facet DOFs
    return np.concatenate(blocks, axis=1).T.astype(np.int64)


#: elements per block in the simplex fast path; bounds the dense work arrays to a few hundred MB
_SIMPLEX_BLOCK = 60_000


def _simplex_matrices(mesh: skfem.Mesh, node_dofs: np.ndarray, lam: np.ndarray, mu: np.ndarray,
                      rho: np.ndarray | None) -> tuple[sp.csr_matrix, sp.csr_matrix | None]:
    """Stiffness and consistent mass of linear triangles/tetrahedra with constant strain.

    Same matrices as the scikit-fem forms (exact integration), computed as B^T D B per element
    in numpy blocks: scikit-fem's generic vector assembly takes ~30 s for 100,000 DOFs.
    """
    dim = mesh.dim()
    n_nodes = dim + 1
    size = node_dofs.size
    stiffness = sp.csr_matrix((size, size))
    mass = None if rho is None else sp.csr_matrix((size, size))
    identity = np.eye(dim)
    node_mass = (np.ones((n_nodes, n_nodes)) + np.eye(n_nodes)) / (n_nodes * (n_nodes + 1))
    for start in range(0, mesh.t.shape[1], _SIMPLEX_BLOCK):
        block = slice(start, start + _SIMPLEX_BLOCK)
        elements = mesh.t[:, block].T
        corners = mesh.p.T[elements]
        edges = np.swapaxes(corners[:, 1:] - corners[:, :1], 1, 2)
        # rows of the inverse edge matrix are the gradients of barycentric coordinates 1..d
        inverse = np.linalg.inv(edges)
        gradients = np.concatenate([-inverse.sum(axis=1, keepdims=True), inverse], axis=1)
        measure = np.abs(np.linalg.det(edges)) / math.factorial(dim)
        # K_(a i)(b j) = V [lam g_ai g_bj + mu (delta_ij g_a.g_b + g_aj g_bi)]
        volumetric = np.einsum("eai,ebj->eaibj", gradients, gradients)
        shear = np.einsum("eab,ij->eaibj", np.einsum("eak,ebk->eab", gradients, gradients), identity) \
            + np.einsum("eaj,ebi->eaibj", gradients, gradients)
        local = lam[block, 0, None, None, None, None] * volumetric + mu[block, 0, None, None, None, None] * shear
        local *= measure[:, None, None, None, None]
        dofs = node_dofs[elements].reshape(len(elements), -1)
        rows = np.repeat(dofs, dofs.shape[1], axis=1).ravel()
        cols = np.tile(dofs, (1, dofs.shape[1])).ravel()
        stiffness = stiffness + sp.csr_matrix((local.ravel(), (rows, cols)), shape=(size, size))
        if mass is not None:
            local_mass = (rho[block, 0] * measure)[:, None, None, None, None] \
                * np.einsum("ab,ij->aibj", node_mass, identity)[None]
            mass = mass + sp.csr_matrix((local_mass.ravel(), (rows, cols)), shape=(size, size))
    return stiffness, mass


#: elements per block of the quad/hex assembly: bounds its work arrays (~60 kB per element
#: for trilinear hexahedra) to about 0.25 GB whatever the mesh size.
_VECTOR_BLOCK = 4096


def _vector_form_matrices(mesh: skfem.Mesh, element: skfem.Element, intorder, lam: np.ndarray,
                          mu: np.ndarray, rho: np.ndarray | None):
    """Isotropic elasticity (and consistent mass) on any vector basis: the strain of each local
    basis function is computed once and all local pairs are formed by one einsum (scikit-fem's
    generic form evaluates both strains for every pair, ~30x slower for hexahedra). Blocks of
    elements are assembled one after the other, each with a basis of its own, so that memory
    stays bounded (a basis over all elements holds 18 kB per hexahedron)."""
    n_elements = mesh.t.shape[1]
    stiffness, mass = None, None
    for start in range(0, n_elements, _VECTOR_BLOCK):
        block = np.arange(start, min(start + _VECTOR_BLOCK, n_elements))
        basis = skfem.Basis(mesh, element, intorder=intorder, elements=block)
        strains = np.array([sym_grad(basis.basis[i][0]) for i in range(basis.Nbfun)])  # (b, d, d, e, q)
        dim = strains.shape[1]
        trace_ = np.einsum("biieq->beq", strains)
        stress = (2.0 * mu[None, None, None, block, None] * strains
                  + lam[None, None, None, block, None] * trace_[:, None, None] * np.eye(dim)[None, :, :, None, None])
        parts = [np.einsum("aijeq,bijeq,eq->eab", strains, stress, basis.dx, optimize=True)]
        if rho is not None:
            values = np.array([np.asarray(basis.basis[i][0]) for i in range(basis.Nbfun)])  # (b, d, e, q)
            parts.append(np.einsum("aieq,bieq,eq->eab", values, values, rho[block, None] * basis.dx,
                                   optimize=True))
        dofs = basis.element_dofs  # (b, e)
        rows = np.broadcast_to(dofs.T[:, :, None], parts[0].shape).ravel()
        cols = np.broadcast_to(dofs.T[:, None, :], parts[0].shape).ravel()
        matrices = [sp.csr_matrix((local.ravel(), (rows, cols)), shape=(basis.N, basis.N)) for local in parts]
        stiffness = matrices[0] if stiffness is None else stiffness + matrices[0]
        if rho is not None:
            mass = matrices[1] if mass is None else mass + matrices[1]
    return stiffness, mass


def assemble_elastic_body(
    mesh: skfem.Mesh,
    youngs_modulus,
    poisson_ratio,
    density=None,
    *,
    plane_strain: bool = True,
    quadratic: bool = False,
) -> ElasticBody:
    """Assemble stiffness (and mass) of an isotropic linear-elastic body.

    youngs_modulus: MPa, poisson_ratio: -, density: t/mm^3; each a scalar or one value per element.
    2D meshes are plane strain (3D Lamé formulas, unit thickness 1 mm) unless
    ``plane_strain=False`` (plane stress). ``quadratic=True`` uses P2 elements on a linear mesh;
    quadratic meshes (MeshTet2, MeshTri2) always use P2.
    """
    dim = mesh.dim()
    element = _element_for(mesh, quadratic)
    # Trilinear hexahedra: 2×2×2 Gauss points, the standard full integration (scikit-fem's
    # default uses 64 points per element, 8x the cost for the same matrices on parallelepipeds).
    intorder = 3 if isinstance(element, skfem.ElementHex1) else None
    # The body keeps the basis for its DOF layout (doflocs, nodal DOFs); quadrature data over
    # every element would cost 18 kB per hexahedron, so it holds one element's only.
    basis = skfem.Basis(mesh, skfem.ElementVector(element), intorder=intorder, elements=np.array([0]))
    n_elements = mesh.t.shape[1]
    young = _per_element(youngs_modulus, n_elements, "youngs_modulus")
    poisson = _per_element(poisson_ratio, n_elements, "poisson_ratio")
    if np.any(young <= 0):
        raise InputError("youngs_modulus must be positive (MPa)")
    if np.any((poisson <= -1) | (poisson >= 0.5)):
        raise InputError("poisson_ratio must lie in (-1, 0.5)")
    lame = lame_parameters if (dim == 3 or plane_strain) else plane_stress
    lam, mu = lame(young, poisson)

    @skfem.BilinearForm
    def elastic_energy(u, v, w):
        strain = sym_grad(u)
        stress = 2.0 * w["mu"] * strain + w["lam"] * eye(trace(strain), strain.shape[0])
        return ddot(stress, sym_grad(v))

    rho = None
    if density is not None:
        rho = _per_element(density, n_elements, "density")
        if np.any(rho <= 0):
            raise InputError("density must be positive (t/mm^3)")
    node_dofs = _node_dofs(basis, dim)
    if type(mesh) in (skfem.MeshTri1, skfem.MeshTet1) and not quadratic:
        stiffness, mass = _simplex_matrices(mesh, node_dofs, lam, mu, rho)
    else:
        stiffness, mass = _vector_form_matrices(
            mesh, skfem.ElementVector(element), intorder, np.asarray(lam, float).reshape(-1),
            np.asarray(mu, float).reshape(-1), None if rho is None else np.asarray(rho, float).reshape(n_elements, -1)[:, 0])
    return ElasticBody(mesh=mesh, basis=basis, dim=dim, stiffness=stiffness, mass=mass, node_dofs=node_dofs)
