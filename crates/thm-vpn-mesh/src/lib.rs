//! # thm-vpn-mesh — the virtual pore network mesh
//!
//! The mesh of Krzaczek, Nitka & Tejchman (2023), Sect. 2.2 and 2.4 (Fig. 3): the spheres of
//! a single layer are projected on the mid-plane as circles; the pore space between them and
//! the circles themselves are triangulated; pore triangles are *virtual pores* (VPs, fluid
//! cells), circle triangles are solid cells owned by one sphere; fluid cells are linked by T2T
//! channels (A-Eq. 9) and S2S channels (A-Eq. 8). Between remeshes the mesh moves with the
//! spheres and gives every cell its volume rate dV/dt (the DEM → CFD term of A-Eq. 25); when
//! the packing has changed enough, a new mesh is built and the cell contents are carried over
//! conservatively.
//!
//! It does **not** solve flow or heat (`thm-vpn-flow`, `thm-fvm-heat` consume [`PoreMesh`]),
//! compute contact stresses (the caller passes σ_n per contact), or write files itself: the
//! shared `thm-io` writers take the arrays of [`export`] (VTU) and the [`picture`] of a mesh
//! (PNG).
//!
//! Units: SI throughout — lengths m, areas m², volumes `area × thickness` m³, stresses Pa,
//! angles rad.
//!
//! ## Public seam
//!
//! - [`PoreMesh`]: struct-of-arrays cells, faces and channels with their geometry (what the
//!   solvers read). [`PoreMesh::from_triangles`] and [`PoreMesh::structured_rectangle`] build
//!   one from given triangles.
//! - [`mesh_packing`]`(circles, contacts, settings) -> `[`PackingMesh`]: the mesher. A
//!   `PackingMesh` is the `PoreMesh` plus what ties it to the circles: vertex anchors, the cuts
//!   ([`Chords`]), each contact's S2S channel, the solid cells of each circle.
//! - [`MeshMotion::update`]: moves the mesh with the circle state ([`CircleMotion`]) and gives
//!   dV/dt per cell; [`remesh_needed`] says when to rebuild.
//! - [`RemapOperator`]: `new(old, new)` then `apply(filter, old_values, new_values)` for every
//!   extensive field.
//!
//! ## The mesher (stages in [`mesher`])
//!
//! 1. **Discretisation.** Every circle boundary carries a uniform angular grid of
//!    `segments_per_circle` points (`θ_k = 2πk/n`); the boundary polygons are inscribed.
//! 2. **Cutting the overlaps along the contact chords.** Paper A (after its ref. 24) "determines the
//!    contact lines and deletes the overlapping areas" without saying how a lens is shared. We
//!    cut along the *radical line* of each overlapping pair, `|x − c_a|² − r_a² = |x − c_b|² −
//!    r_b²`, which is the line through the two intersection points: the common chord. For three
//!    or more mutually overlapping circles the chords meet at the radical centre, so the cut
//!    pieces (the power diagram restricted to the union of the discs) tile the union without
//!    gaps or double cover; a circle inside another gets no cells, two identical circles give
//!    their region to the first. Each solid polygon is `disc ∩ power cell` with the arcs
//!    replaced by the grid points between the chord ends (grid points closer than a quarter
//!    step to a chord end are skipped). Shared vertices (chord ends, radical centres, crossings
//!    of the box) are computed once from a canonical key, so neighbouring polygons share them
//!    bit for bit; vertices closer than `snap_tolerance × r` are merged (tangent circles) and
//!    put exactly on a box side when that close to it, `r` being the radius of the smallest
//!    circle they belong to, at most the mean radius (so a circle many decades smaller than the
//!    others keeps its own grid points apart), and the distance at least 8 ulps of the
//!    coordinates.
//! 3. **Triangulation.** A constrained Delaunay triangulation (`spade`, bulk loaded) of all
//!    polygon vertices, with every polygon edge and the box sides as constraints; the centre of
//!    each circle whose polygon keeps it at least `r/4` from every edge is added as a Steiner
//!    point, so solid cells are wedges rather than slivers across the disc.
//! 4. **Classification.** A triangle is a solid cell of circle `i` when its three corners are
//!    vertices of polygon `i` (or its centre) — exact, since the polygons are convex and
//!    constrained — and a fluid cell otherwise.
//! 5. **Outline.** [`Outline::Box`]: the rectangle, circles clipped by it (a side is a power
//!    cell half-plane as well). [`Outline::AlphaShape`] (the paper's "Alfa Shapes", A-Sect. 2.4,
//!    Bernardini & Bajaj 1997): starting from the convex hull, fluid triangles with a face on
//!    the current outline and circumradius > α are removed until none is left; solid cells and
//!    pores enclosed by solid stay, so the specimen keeps its inner pores and its narrow
//!    surface cusps.
//! 6. **Locality order.** The triangles are sorted along the Z-order (Morton) curve of their
//!    centroids and the vertices numbered in order of first use, so faces and channels, which
//!    are created in cell order, follow too: what is near in space is near in memory, and the
//!    passes over the mesh (geometry update, heat and flow stencils, remap) gather from a few
//!    cache lines. Vertices are grouped by their kinematics (free on one circle, as points
//!    on an arc are, first; then two and three anchors; then those held on a box side), each
//!    group in order of first use, so the vertex kinematics takes its branches without
//!    misprediction. Cell, vertex and face numbers therefore depend on
//!    positions, not on the order of the circles.
//! 7. **Faces, geometry, channels.** [`PoreMesh::from_triangles`] creates faces, areas,
//!    centroids, normals, boundary sides and the T2T channels; the mesher adds the S2S channels.
//!
//! Accuracy: the solid area of every circle (and of the union) converges to the exact cut
//! area at second order, error ≈ `(2π/n)²/6` of the area (measured: 3.6–4.0× smaller per
//! doubling of `n`; see `tests/mesher.rs` and the verification case).
//!
//! ## Channels
//!
//! - **T2T** (A-Eq. 9): `h = γ e cos(90° − ω)` between two fluid cells sharing an edge of length
//!   `e`, with `ω` the angle between that edge and the line joining the two centroids, i.e.
//!   `h = γ e sin ω = γ e |n·d|/|d|` (`n` the unit edge normal, `d` the centroid offset): a
//!   channel crossing its edge squarely gets the full edge, a grazing one almost nothing.
//!   Length: distance between the centroids (A-Sect. 2.2).
//! - **S2S** (A-Eq. 8): `h = β (h_inf + (h_0 − h_inf) exp(−1.5·10⁻⁷ σ_n))`, σ_n in Pa,
//!   compression positive (the coefficient is dimensional, 1/Pa: at σ_n = 10 MPa the
//!   exponential is e^(−1.5)). A tensile σ_n is taken as zero, giving `β h_0`, so an opened
//!   contact does not get an aperture that grows without bound. Defaults are Table 1:
//!   `h_inf = 5.75·10⁻⁷ m`, `h_0 = 3.25·10⁻⁶ m`, `β = 1.2`, `γ = 0.0115`; Table 1 labels β as
//!   "Eq. 9" and γ as "Eq. 10", off by one from the text, where β appears in Eq. 8 and γ in
//!   Eq. 9 — we follow the text. The channel joins the fluid cells at the **two ends of the
//!   cut**: at each end vertex, the incident fluid cell whose centroid is nearest to it. A
//!   contact gets no S2S channel when its circles do not overlap (the gap between them is pore
//!   space already crossed by T2T channels), when an end of its cut lies inside the solid
//!   (three or more circles meeting there: no pore touches it), or when both ends see the same
//!   fluid cell. Its length is the distance between the two centroids.
//!
//! Thickness (cell volume = area × thickness): the largest sphere diameter unless given
//! (A-Sect. 2.4: "the specimen thickness … equal to the largest diameter of spheres").
//!
//! ## Motion between remeshes ([`motion`])
//!
//! Each vertex is anchored to the circles it lies on (an arc point to one, a chord end to two,
//! a radical centre to three, a centre to its circle). Anchor `k` carries the mesh-time point
//! `x₀` with its circle: `y_k = c_k + r_k R(φ_k) (x₀ − c⁰_k)/r⁰_k`; the vertex is the mean of its
//! `y_k`, so arc points stay exactly on their circle under translation, rotation and radius
//! change. Vertex velocities are the exact time derivative,
//! `mean_k [v_k + ω_k ẑ×(y_k − c_k) + (ṙ_k/r_k)(y_k − c_k)]`; box-side vertices keep their
//! normal coordinate, corners are fixed. The cell area rate is the exact derivative of the
//! triangle area, `dA/dt = ½[(u_b − u_a)×(p_c − p_a) + (p_b − p_a)×(u_c − u_a)]`, and
//! `dV/dt = thickness · dA/dt`. With a box outline the rates sum to zero to round-off. The
//! T2T apertures (A-Eq. 9) are recomputed on the moved triangles; the S2S apertures follow the
//! contact stresses through [`PackingMesh::update_s2s_apertures`]. [`MeshMotion::update`] is
//! one allocation-free pass per entity over precomputed index arrays (anchor rows per vertex;
//! triangle corners for areas, centroids and dV/dt together; face ends; channel cells), the
//! same numbers bit for bit as the stages called one by one.
//!
//! ## Remesh trigger
//!
//! Paper A tracks "displacements, overlaps and size changes" and leaves the threshold to a
//! parametric study. [`remesh_needed`] fires when, since the mesh was built, a centre moved more
//! than `max_displacement · r` (default 0.05), a circle turned more than `max_rotation` grid
//! steps (0.25), a radius changed by more than `max_radius_change` (1 %), a cut pair's overlap
//! changed by more than `max_overlap_change · min(r)` (0.02), two circles in contact overlap
//! without a cut (topology change), or any cell has area ≤ 0.
//!
//! ## Conservative remap ([`remap`])
//!
//! Old and new triangles are intersected exactly (Sutherland–Hodgman, after a separating-edge
//! test; the new cells meeting an old one are found by a walk over the new mesh from the cell
//! holding its centroid, stopping once the old cell is covered); an old cell's content
//! is split over the *admissible* new cells it overlaps (fluid fields → fluid cells; solid
//! fields → solid cells of the same sphere, else any solid) in proportion to the overlap areas,
//! normalised by their sum. So the part of an old pore now covered by solid does not destroy
//! mass: that mass is spread over the part of the old pore that is still pore. An old cell
//! with no admissible overlap (a pore closed) gives its content to the nearest admissible new
//! cell (breadth-first over the new faces from the cells it overlaps). Totals are conserved to
//! round-off (tests: 1e-12 relative). Pressures and phase fractions are not remapped; they
//! follow from the remapped masses through the closure (A-Sect. 2.4, A-Eq. 29).
//!
//! ## Picture
//!
//! [`picture::write_mesh_png`] draws a mesh through `thm-io`: fluid cells blue, solid cells in
//! a few sand shades (touching spheres differ), channels as lines. The verification case
//! `vpn_mesh/paper_bar` writes the 20 × 80 mm bar to `target/verify/vpn_mesh/paper_bar/mesh.png`;
//! `docs/images/vpn_mesh_bar.png` is a copy:
//!
//! ![VPN mesh of the 20 × 80 mm bar](../../docs/images/vpn_mesh_bar.png)
//!
//! ## Robustness
//!
//! Degenerate input never panics: no circles (box: two fluid triangles; alpha shape:
//! [`MeshError::NoCircles`]), one circle, duplicate centres, collinear centres, tangent
//! circles, deep overlaps and circles inside others give valid meshes (tests in
//! `tests/degenerate.rs` and property tests over random circles); NaN, infinite, zero or
//! negative radii and non-finite centres are [`MeshError`]s naming the circle. Constraint
//! edges that would still cross after snapping are reported as
//! [`MeshError::ConstraintConflict`] rather than giving a wrong mesh.
//!
//! ## Changes to the shared types
//!
//! [`PoreMesh::from_triangles`] builds faces through per-vertex edge lists instead of a hash
//! map (same faces, same order, same errors; faster). Everything else of `mesh.rs`
//! is unchanged; new methods (in [`export`]) list fluid–solid interface faces and contact
//! faces and give VTU-ready arrays.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod circles;
mod error;
pub mod export;
mod mesh;
pub mod mesher;
pub mod motion;
pub mod packing;
pub mod picture;
pub mod remap;

pub use error::MeshError;
pub use mesh::{
    BoundarySide, CellKind, ChannelKind, Channels, FaceKind, NONE, PoreMesh, T2tApertureLaw,
    TopologyError,
};
pub use mesher::{
    Chords, Circle, Contact, MeshParams, MeshSettings, Outline, PackingMesh, S2sApertureParams,
    mesh_packing,
};
pub use motion::{
    CircleMotion, MeshMotion, RemeshCriteria, RemeshCriteriaParams, RemeshReason, VertexAnchors,
    VertexConstraint, inverted_cell, remesh_needed,
};
pub use picture::{PictureStyle, write_mesh_png};
pub use remap::{CellFilter, RemapOperator};

#[cfg(feature = "verification")]
pub mod verification;
