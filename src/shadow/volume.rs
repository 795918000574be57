//! Stenciled shadow volumes on the CPU (paper section 4; thesis chapter 3), GL-free.
//!
//! Casters are grouped by owner (the world; each model, in its own model space so its caps reuse
//! the exact vertex arithmetic of its lit pass) and split into connected components, which are the
//! unit of the depth-pass / depth-fail choice. Per light:
//! 1. triangles are classified as facing the light (`n·(L - c) > -ε |L - c|`, Forsyth's ε);
//! 2. edges are extruded by a rule: the paper's world rule (skip an edge only when it is shared by
//!    exactly two facing triangles; otherwise every facing triangle on it extrudes it), extrude
//!    every edge of every facing triangle (the paper's first fix), or the naive 2-manifold rule;
//! 3. side quads run from the edge to infinity, P' = (P.xyz·L.w − L.xyz·P.w, 0) (or a finite
//!    distance); depth-fail adds the facing triangles as the front cap and their flipped
//!    extrusions as the back cap.

use super::edges::{Connectivity, Edge};
use crate::geometry::Aabb;
pub use crate::options::{EdgeRule, Extrusion};
use crate::scene::{Scene, SurfaceOwner};
use glam::{DVec3, Mat4, Vec3};
use serde::Serialize;

/// Whether a component's volume is counted in front of (depth-pass) or behind (depth-fail) the
/// visible surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Counting {
    ZPass,
    ZFail,
}

/// A connected set of caster triangles.
#[derive(Debug, Clone)]
pub struct Component {
    /// Triangles of the group's connectivity.
    pub triangles: Vec<u32>,
    /// Edges of the group's connectivity whose triangles belong to this component.
    pub edges: Vec<u32>,
    /// Bounds in the group's space.
    pub bounds: Aabb,
    /// Whether it holds triangles of an alpha-tested material (rays pass through their holes
    /// into the volume through its front cap, so it must count depth-fail).
    pub alpha_tested: bool,
    /// Whether its connected surface has an open edge (one triangle). Depth-pass on such a
    /// piece changed masks on open Quake 3 worlds (ctf_compromise: 20 179 pixels beyond the
    /// edge band against the paper's depth-fail), so the planner keeps it at depth-fail
    /// (`plan.open_depth_fail`). Chunks take their component's.
    pub open: bool,
}

/// Which piece of a caster group a volume is extruded from: a whole connected component (the
/// paper's frame) or one chunk of one (the planner's unit, `plan.cull_casters`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PieceRef {
    Component(usize),
    Chunk(usize),
}

/// The casters of one owner, welded, with their connectivity and components.
#[derive(Debug, Clone)]
pub struct CasterGroup {
    pub owner: SurfaceOwner,
    pub connectivity: Connectivity,
    pub components: Vec<Component>,
    /// The same triangles in pieces of at most [`CHUNK_TRIANGLES`]: each component split in
    /// space. A piece's volume is closed on its own (its cut edges are extruded like open
    /// edges), so the planner can cull pieces of a large connected world one by one.
    pub chunks: Vec<Component>,
    /// How the components were cut into `chunks`, children before parents: a component of
    /// more than one chunk has a node for each cut.
    pub chunk_tree: Vec<ChunkNode>,
    /// The owner's pose it was built from (`ModelInstance::pose`; 0 for the world).
    pub pose: u64,
}

/// One cut of [`split_chunks`]: the chunks `first..end` (consecutive: each half's chunks follow
/// one another) are the halves `first..mid` and `mid..end` of one piece of a component. Two
/// neighbouring halves share the edges along the cut, where each half's volume has a side the
/// other's cancels; drawn as one piece, those sides go away.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkNode {
    pub first: usize,
    pub mid: usize,
    pub end: usize,
}

/// The part of space where a caster inside `caster` can shadow receivers within `radius` of the
/// light: the union of segments from each caster point away from the light to the range's edge
/// lies in the hull of the box and its image scaled about the light by T = radius / (distance to
/// the box); its bounds, clipped to the range's box.
pub fn shadow_bounds(caster: &Aabb, light: Vec3, radius: f32) -> Aabb {
    let range = Aabb {
        min: light - radius,
        max: light + radius,
    };
    let nearest = light.clamp(caster.min, caster.max);
    let d = nearest.distance(light);
    if d <= 1e-3 {
        // The light touches or is inside the box: the shadow can go anywhere in range.
        return range;
    }
    let t = (radius / d).max(1.0);
    let corners = caster.corners();
    let pushed = corners.map(|c| light + (c - light) * t);
    Aabb::from_points(corners.into_iter().chain(pushed)).intersection(&range)
}

/// The receivers a volume has to be right for, in the group's space, and the light's range:
/// a facing triangle whose shadow can reach none of them is treated as not facing. Its shadow
/// would hold no receiver, and the rest of the volume stays closed around the cut (planner).
#[derive(Debug, Clone, Copy)]
pub struct ReceiverCull<'a> {
    pub boxes: &'a [Aabb],
    pub radius: f32,
    /// End the volume just past the receivers instead of at infinity (see [`truncation`]).
    pub truncate: bool,
}

/// How far behind a triangle's plane a receiver must reach to be in its shadow: the exact
/// reference lifts its rays 0.01 units off surfaces, so it resolves nothing closer either.
const BEHIND: f64 = 0.01;

/// Beyond the farthest receiver point a truncated volume's far cap keeps this margin (world
/// units, plus 1% of the depth), so that it never meets a receiver in the depth test.
const FAR_CAP_MARGIN: f64 = 1.0;

/// Scale factors above this (a light almost touching a facing triangle) keep the volume
/// infinite: a far cap so far out would buy little and cost precision.
const MAX_TRUNCATION: f64 = 1.0e4;

/// Whether facing triangle `t`'s shadow can reach one of `boxes` (those already known to meet
/// its piece's shadow), and if so how far its volume must reach to hold every point of them
/// that it shadows. Its shadow is the part of the pyramid from the light through the triangle
/// that lies behind the triangle's plane, and a box must reach inside all four of those planes
/// (a conservative test: a box near an edge of the pyramid may pass).
///
/// The reach is a scale about the light (the triangle scaled by it is the volume's far cap; the
/// infinite volume has ∞): a point P behind the triangle on the ray from the light through x
/// sits at λ = 1 + h(P) / d, where d is the light's height above the triangle's plane and h(P)
/// the point's depth behind it, largest at a box corner; within the range λ ≤ radius / |x − L|
/// as well. Up to that scale the truncated volume is the infinite one.
fn shadow_reach(
    c: &Connectivity,
    t: usize,
    light: Vec3,
    radius: f32,
    boxes: &[&Aabb],
) -> Option<f64> {
    let l = light.as_dvec3();
    let corners = c.triangles[t].map(|v| c.positions[v as usize]);
    let bounds = Aabb::from_points(corners);
    let in_range = shadow_bounds(&bounds, light, radius);
    let tri = corners.map(|p| p.as_dvec3());
    // The triangle's plane turned toward the light: a triangle cast from behind
    // (`VolumeSettings::two_sided`) shadows its own front side.
    let plane = &c.planes[t];
    let toward = if plane.normal.dot(l) + plane.d < 0.0 {
        -1.0
    } else {
        1.0
    };
    let (normal, d) = (plane.normal * toward, plane.d * toward);
    // Planes (n, d), inside where n·x + d >= 0: behind the triangle, and the pyramid's sides.
    let mut planes = vec![(-normal, -d - BEHIND)];
    for k in 0..3 {
        let (a, b, opposite) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
        let mut n = (b - a).cross(a - l);
        if n.length_squared() < 1e-24 {
            continue;
        }
        n = n.normalize();
        if n.dot(opposite - a) < 0.0 {
            n = -n;
        }
        planes.push((n, -n.dot(a)));
    }
    let nearest = light.clamp(bounds.min, bounds.max).distance(light) as f64;
    let by_range = if nearest > 1e-3 {
        radius as f64 * 1.01 / nearest + 0.01
    } else {
        f64::INFINITY
    };
    let height = normal.dot(l) + d;
    let behind = -normal;
    let mut reach: Option<f64> = None;
    for b in boxes {
        if !b.intersects(&in_range)
            || !planes
                .iter()
                .all(|(n, d)| n.dot(furthest_corner(b, *n)) + d >= 0.0)
        {
            continue;
        }
        let cut = b.intersection(&in_range);
        let deepest = (behind.dot(furthest_corner(&cut, behind)) - d).max(0.0);
        let by_box = if height > 1e-6 {
            1.0 + (deepest * 1.01 + FAR_CAP_MARGIN) / height
        } else {
            f64::INFINITY
        };
        let needed = by_box.min(by_range);
        reach = Some(reach.map_or(needed, |r| r.max(needed)));
    }
    reach
}

/// [`Aabb::furthest_corner`] for an f64 direction, in f64.
fn furthest_corner(b: &Aabb, n: DVec3) -> DVec3 {
    b.furthest_corner(n.cmpge(DVec3::ZERO)).as_dvec3()
}

/// Largest piece of [`CasterGroup::chunks`].
pub const CHUNK_TRIANGLES: usize = 256;

/// Splits `tris` at the median centroid along the longest axis until pieces are small enough,
/// recording each cut in `tree`.
fn split_chunks(
    c: &Connectivity,
    tris: Vec<u32>,
    out: &mut Vec<Vec<u32>>,
    tree: &mut Vec<ChunkNode>,
) {
    if tris.len() <= CHUNK_TRIANGLES {
        out.push(tris);
        return;
    }
    let centroid = |t: u32| {
        let [a, b, d] = c.triangles[t as usize].map(|v| c.positions[v as usize]);
        (a + b + d) / 3.0
    };
    let bounds = Aabb::from_points(tris.iter().map(|&t| centroid(t)));
    let size = bounds.max - bounds.min;
    let axis = if size.x >= size.y && size.x >= size.z {
        0
    } else if size.y >= size.z {
        1
    } else {
        2
    };
    let mut tris = tris;
    tris.sort_by(|&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
    let right = tris.split_off(tris.len() / 2);
    let first = out.len();
    split_chunks(c, tris, out, tree);
    let mid = out.len();
    split_chunks(c, right, out, tree);
    tree.push(ChunkNode {
        first,
        mid,
        end: out.len(),
    });
}

/// Every caster group of a scene, built once per scene.
#[derive(Debug, Clone, Default)]
pub struct CasterGroups {
    pub groups: Vec<CasterGroup>,
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
}

impl CasterGroup {
    /// Welds and connects `triangles` (in the owner's space), then splits them into components.
    pub fn build(owner: SurfaceOwner, triangles: Vec<[Vec3; 3]>) -> CasterGroup {
        let connectivity = Connectivity::build(triangles);
        let n = connectivity.triangles.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        for e in &connectivity.edges {
            let tris = connectivity.triangles_of(e);
            for w in tris.windows(2) {
                let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
                if a != b {
                    parent[a as usize] = b;
                }
            }
        }
        let mut index_of_root = std::collections::HashMap::new();
        let mut components: Vec<Component> = Vec::new();
        let mut tri_component = vec![0u32; n];
        for t in 0..n as u32 {
            let root = find(&mut parent, t);
            let c = *index_of_root.entry(root).or_insert_with(|| {
                components.push(Component {
                    triangles: Vec::new(),
                    edges: Vec::new(),
                    bounds: Aabb::EMPTY,
                    alpha_tested: false,
                    open: false,
                });
                components.len() as u32 - 1
            });
            tri_component[t as usize] = c;
            let comp = &mut components[c as usize];
            comp.triangles.push(t);
            for v in connectivity.triangles[t as usize] {
                comp.bounds.extend(connectivity.positions[v as usize]);
            }
        }
        // An edge's triangles are connected through it, so its first triangle's component is all
        // of theirs.
        for (ei, e) in connectivity.edges.iter().enumerate() {
            let tris = connectivity.triangles_of(e);
            let c = &mut components[tri_component[tris[0] as usize] as usize];
            c.edges.push(ei as u32);
            c.open |= tris.len() == 1;
        }
        let (mut pieces, mut chunk_tree) = (Vec::new(), Vec::new());
        for comp in &components {
            split_chunks(
                &connectivity,
                comp.triangles.clone(),
                &mut pieces,
                &mut chunk_tree,
            );
        }
        let mut tri_chunk = vec![0u32; n];
        let mut chunks: Vec<Component> = pieces
            .into_iter()
            .enumerate()
            .map(|(i, triangles)| {
                let mut bounds = Aabb::EMPTY;
                for &t in &triangles {
                    tri_chunk[t as usize] = i as u32;
                    for v in connectivity.triangles[t as usize] {
                        bounds.extend(connectivity.positions[v as usize]);
                    }
                }
                let open = triangles
                    .first()
                    .is_some_and(|&t| components[tri_component[t as usize] as usize].open);
                Component {
                    triangles,
                    edges: Vec::new(),
                    bounds,
                    alpha_tested: false,
                    open,
                }
            })
            .collect();
        // An edge belongs to every piece holding one of its triangles.
        for (ei, e) in connectivity.edges.iter().enumerate() {
            let mut seen: Vec<u32> = Vec::new();
            for &t in connectivity.triangles_of(e) {
                let c = tri_chunk[t as usize];
                if !seen.contains(&c) {
                    seen.push(c);
                    chunks[c as usize].edges.push(ei as u32);
                }
            }
        }
        CasterGroup {
            pose: 0,
            owner,
            connectivity,
            components,
            chunks,
            chunk_tree,
        }
    }

    /// The piece `r` names.
    pub fn piece(&self, r: PieceRef) -> &Component {
        match r {
            PieceRef::Component(i) => &self.components[i],
            PieceRef::Chunk(i) => &self.chunks[i],
        }
    }

    /// Marks the components and chunks holding a triangle whose input triangle (in the order
    /// given to [`CasterGroup::build`]) `alpha_tested` flags.
    pub fn with_alpha_tested(mut self, alpha_tested: &[bool]) -> CasterGroup {
        let c = &self.connectivity;
        let flagged = |t: &u32| {
            let source = c.source_triangle[*t as usize] as usize;
            alpha_tested.get(source).copied().unwrap_or(false)
        };
        for piece in self.components.iter_mut().chain(self.chunks.iter_mut()) {
            piece.alpha_tested = piece.triangles.iter().any(flagged);
        }
        self
    }

    /// The triangles of `piece` that `keep` says yes to, as a piece of their own: the edges
    /// of `piece` with a triangle `keep` accepts (one outside `piece` adds an edge that
    /// extrudes nothing: only the subset's triangles face the light in its build) and their
    /// bounds. Its volume is closed along the cut like a chunk's.
    pub fn subset(&self, piece: &Component, keep: impl Fn(u32) -> bool) -> Component {
        let c = &self.connectivity;
        let triangles: Vec<u32> = piece
            .triangles
            .iter()
            .copied()
            .filter(|&t| keep(t))
            .collect();
        let edges = piece
            .edges
            .iter()
            .copied()
            .filter(|&e| {
                c.triangles_of(&c.edges[e as usize])
                    .iter()
                    .any(|&t| keep(t))
            })
            .collect();
        let mut bounds = Aabb::EMPTY;
        for &t in &triangles {
            for v in c.triangles[t as usize] {
                bounds.extend(c.positions[v as usize]);
            }
        }
        Component {
            alpha_tested: piece.alpha_tested,
            open: piece.open,
            triangles,
            edges,
            bounds,
        }
    }

    /// The chunks `first..end` as one piece: their triangles, their edges (once each) and
    /// bounds. Its volume is theirs less the sides along the cuts between them.
    pub fn chunk_span(&self, first: usize, end: usize) -> Component {
        let span = &self.chunks[first..end];
        let mut edges: Vec<u32> = span.iter().flat_map(|c| c.edges.iter().copied()).collect();
        edges.sort_unstable();
        edges.dedup();
        Component {
            triangles: span
                .iter()
                .flat_map(|c| c.triangles.iter().copied())
                .collect(),
            edges,
            bounds: span.iter().fold(Aabb::EMPTY, |b, c| b.union(&c.bounds)),
            alpha_tested: span.iter().any(|c| c.alpha_tested),
            open: span.iter().any(|c| c.open),
        }
    }
}

impl CasterGroups {
    /// Groups the scene's casting triangles by owner, in each owner's own space.
    pub fn build(scene: &Scene) -> CasterGroups {
        let mut owners: Vec<SurfaceOwner> = Vec::new();
        for s in &scene.surfaces {
            let m = &scene.materials[s.material];
            if m.visible && m.casts_shadows && !owners.contains(&s.owner) {
                owners.push(s.owner);
            }
        }
        CasterGroups {
            groups: owners
                .into_iter()
                .map(|o| CasterGroup::of_owner(scene, o))
                .collect(),
        }
    }

    /// These groups with those of models whose pose changed built again (the scene's
    /// surfaces are the ones these were built from); returns how many were rebuilt.
    pub fn reposed(&self, scene: &Scene) -> (CasterGroups, usize) {
        let mut rebuilt = 0;
        let groups = self
            .groups
            .iter()
            .map(|g| match g.owner {
                SurfaceOwner::Model(m) if scene.models.get(m).is_some_and(|i| i.pose != g.pose) => {
                    rebuilt += 1;
                    CasterGroup::of_owner(scene, g.owner)
                }
                _ => g.clone(),
            })
            .collect();
        (CasterGroups { groups }, rebuilt)
    }

    /// Whether every model group was built from its model's current pose.
    pub fn posed_as(&self, scene: &Scene) -> bool {
        self.groups.iter().all(|g| match g.owner {
            SurfaceOwner::Model(m) => scene.models.get(m).is_some_and(|i| i.pose == g.pose),
            SurfaceOwner::World => true,
        })
    }
}

impl CasterGroup {
    /// The casting triangles of `owner`, welded and connected, with its pose.
    pub fn of_owner(scene: &Scene, owner: SurfaceOwner) -> CasterGroup {
        let mut tris = Vec::new();
        let mut alpha = Vec::new();
        for s in scene.surfaces.iter().filter(|s| s.owner == owner) {
            let m = &scene.materials[s.material];
            if !(m.visible && m.casts_shadows) {
                continue;
            }
            let range = s.first_index as usize..(s.first_index + s.index_count) as usize;
            for t in scene.indices[range].chunks_exact(3) {
                let p = |k: usize| scene.vertices[t[k] as usize].pos();
                tris.push([p(0), p(1), p(2)]);
                alpha.push(m.alpha_test.is_some());
            }
        }
        let pose = match owner {
            SurfaceOwner::Model(m) => scene.models[m].pose,
            SurfaceOwner::World => 0,
        };
        CasterGroup {
            pose,
            ..CasterGroup::build(owner, tris).with_alpha_tested(&alpha)
        }
    }
}

/// Doom 3's test of whether the view may be inside a caster's infinite shadow: the caster's bounds
/// stretched by twice the near distance contain the eye or the light, or the segment from the
/// light to the eye crosses them. When it may not, depth-pass is safe for that caster.
pub fn potentially_inside_shadow(bounds: &Aabb, eye: Vec3, light: Vec3, near: f32) -> bool {
    if bounds.is_empty() {
        return false;
    }
    let stretch = 2.0 * near;
    let (min, max) = (bounds.min - stretch, bounds.max + stretch);
    let inside = |p: Vec3| p.cmpge(min).all() && p.cmple(max).all();
    if inside(eye) || inside(light) {
        return true;
    }
    // Slab test of the segment light → eye against the stretched box.
    let d = eye - light;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for a in 0..3 {
        if d[a].abs() < 1e-12 {
            if light[a] < min[a] || light[a] > max[a] {
                return false;
            }
        } else {
            let (mut ta, mut tb) = ((min[a] - light[a]) / d[a], (max[a] - light[a]) / d[a]);
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// Whether the camera's near-plane rectangle `quad` (corners in order, in the group's space)
/// may lie in the shadow volume of `piece` for a light at `light`: whether some facing
/// triangle meets the hull of the light and the rectangle (every segment from the light to a
/// near-plane point lies in it). A separating-axis test per facing triangle, exact for the
/// convex hull; touching counts as meeting. When false, depth-pass counts start at zero on the
/// near plane for this piece.
pub fn near_plane_shadowed(
    group: &CasterGroup,
    piece: &Component,
    light: DVec3,
    quad: &[DVec3; 4],
    epsilon: f32,
    two_sided: bool,
) -> bool {
    near_plane_triangles(group, piece, light, quad, epsilon, two_sided)
        .next()
        .is_some()
}

/// The facing triangles of `piece` whose shadow may hold part of the near-plane rectangle (the
/// test of [`near_plane_shadowed`], triangle by triangle), in the piece's order. The volume of
/// the other triangles, closed along the cut, holds none of the rectangle: depth-pass counts
/// it correctly.
pub fn near_plane_triangles<'a>(
    group: &'a CasterGroup,
    piece: &'a Component,
    light: DVec3,
    quad: &[DVec3; 4],
    epsilon: f32,
    two_sided: bool,
) -> impl Iterator<Item = u32> + 'a {
    let hull = [light, quad[0], quad[1], quad[2], quad[3]];
    let hull_edges: [DVec3; 8] = [
        quad[0] - light,
        quad[1] - light,
        quad[2] - light,
        quad[3] - light,
        quad[1] - quad[0],
        quad[2] - quad[1],
        quad[3] - quad[2],
        quad[0] - quad[3],
    ];
    let mut hull_faces = [(quad[1] - quad[0]).cross(quad[3] - quad[0]); 5];
    for i in 0..4 {
        hull_faces[i + 1] = hull_edges[i].cross(hull_edges[(i + 1) % 4]);
    }
    let c = &group.connectivity;
    // Two-sided casting: every triangle's shadow counts (the test is blind to winding).
    let facing = if two_sided {
        vec![true; c.triangles.len()]
    } else {
        facing_flags_of(group, piece, light, epsilon)
    };
    let separated = move |axis: DVec3, tri: &[DVec3; 3]| -> bool {
        if axis.length_squared() == 0.0 {
            return false;
        }
        let (mut hmin, mut hmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &hull {
            let d = axis.dot(*p);
            hmin = hmin.min(d);
            hmax = hmax.max(d);
        }
        let (mut tmin, mut tmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in tri {
            let d = axis.dot(*p);
            tmin = tmin.min(d);
            tmax = tmax.max(d);
        }
        hmax < tmin || tmax < hmin
    };
    piece.triangles.iter().copied().filter(move |&t| {
        if !facing[t as usize] {
            return false;
        }
        let tri = c.triangles[t as usize].map(|v| c.positions[v as usize].as_dvec3());
        let tri_edges = [tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]];
        let normal = tri_edges[0].cross(tri_edges[1]);
        if separated(normal, &tri) || hull_faces.iter().any(|&n| separated(n, &tri)) {
            return false;
        }
        !hull_edges
            .iter()
            .any(|h| tri_edges.iter().any(|e| separated(h.cross(*e), &tri)))
    })
}

/// How volumes are built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeSettings {
    pub rule: EdgeRule,
    pub extrusion: Extrusion,
    pub finite_distance: f32,
    /// Forsyth's facing epsilon (cosine): a triangle faces the light when n·l > -ε.
    pub facing_epsilon: f32,
    /// Every triangle casts: those facing away with the opposite winding
    /// (`shadow_volume.casters = both`).
    pub two_sided: bool,
}

/// Volume geometry of one component for one light, as triangles of homogeneous vertices.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VolumeMesh {
    /// Side quads (two triangles each), then front-cap triangles, then back-cap triangles.
    pub vertices: Vec<[f32; 4]>,
    /// Facing triangles left out because their shadow reaches no receiver.
    pub culled: usize,
    pub side_vertices: usize,
    pub cap_vertices: usize,
    /// Edges extruded.
    pub quads: usize,
    /// Facing triangles (each gives a front and a back cap triangle under depth-fail).
    pub facing: usize,
    /// Whether each facing triangle's volume ends just past the receivers it shadows (then
    /// the caps hold the far cap under depth-pass too).
    pub truncated: bool,
}

/// `p` pushed away from the light to `scale` times its offset from it (1: `p` itself); an
/// infinite scale extrudes as the settings say.
fn extrude(p: DVec3, light: DVec3, s: &VolumeSettings, scale: f64) -> [f64; 4] {
    if scale == 1.0 {
        return [p.x, p.y, p.z, 1.0];
    }
    if scale.is_finite() {
        let q = light + (p - light) * scale;
        return [q.x, q.y, q.z, 1.0];
    }
    match s.extrusion {
        // P' = (P.xyz L.w - L.xyz P.w, 0) with P.w = L.w = 1.
        Extrusion::Infinite => {
            let d = p - light;
            [d.x, d.y, d.z, 0.0]
        }
        Extrusion::Finite => {
            let d = (p - light).normalize_or_zero() * s.finite_distance as f64;
            let q = p + d;
            [q.x, q.y, q.z, 1.0]
        }
    }
}

fn to_f32(v: [f64; 4]) -> [f32; 4] {
    v.map(|x| x as f32)
}

/// Which triangles of `component` face a point light at `light` (indexed by the group's
/// triangles; others are false): `n·(L − c) > −ε |L − c|` in f64, with the centroid `c`. A
/// triangle with zero area, or with a corner at the light, never faces it.
pub fn facing_flags(
    group: &CasterGroup,
    component: usize,
    light: DVec3,
    epsilon: f32,
) -> Vec<bool> {
    facing_flags_of(group, &group.components[component], light, epsilon)
}

/// [`facing_flags`] for any piece of the group (a component or a chunk).
pub fn facing_flags_of(
    group: &CasterGroup,
    piece: &Component,
    light: DVec3,
    epsilon: f32,
) -> Vec<bool> {
    let c = &group.connectivity;
    let mut facing = vec![false; c.triangles.len()];
    for &t in &piece.triangles {
        if let Some((d, distance)) = light_offset(c, t, light) {
            facing[t as usize] = d > -(epsilon as f64) * distance;
        }
    }
    facing
}

/// The light's signed distance from triangle `t`'s plane and its distance from the centroid,
/// in f64; None for a triangle without area or with a corner at the light, which never faces
/// it and casts nothing.
fn light_offset(c: &Connectivity, t: u32, light: DVec3) -> Option<(f64, f64)> {
    let pos = |i: u32| c.positions[i as usize].as_dvec3();
    let tri = c.triangles[t as usize];
    let plane = &c.planes[t as usize];
    if plane.normal == DVec3::ZERO || tri.iter().any(|&v| pos(v) == light) {
        return None;
    }
    let centroid = (pos(tri[0]) + pos(tri[1]) + pos(tri[2])) / 3.0;
    let to_light = light - centroid;
    Some((plane.normal.dot(to_light), to_light.length()))
}

/// Where a point light stands to a triangle's plane, for two-sided casting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightSide {
    /// On the side the triangle's normal points to.
    Front,
    /// On the other side: the triangle casts with the opposite winding.
    Behind,
    /// In its plane (within [`IN_PLANE`]), at a corner, or the triangle has no area: its
    /// volume has no thickness and it casts none. Its edges to casting neighbours become
    /// silhouettes, which keeps the shadow of a closed caster whose faces all hold the light
    /// or face away from it (a light on its vertex or edge).
    InPlane,
}

/// A light closer to a triangle's plane than this fraction of its distance to the centroid
/// lies in the plane: f32 positions put a light meant to be on a tilted plane about 1e-7 of
/// the coordinates off it, and either side's thin volume would then be right anyway; what
/// must not happen is an exact zero read as one side, which turns a face that casts nothing
/// into a neighbour that hides the silhouette.
pub const IN_PLANE: f64 = 1e-9;

/// [`LightSide`] of every triangle of `piece` (indexed by the group's triangles; others are
/// `InPlane`), in f64.
pub fn light_sides_of(group: &CasterGroup, piece: &Component, light: DVec3) -> Vec<LightSide> {
    let c = &group.connectivity;
    let mut sides = vec![LightSide::InPlane; c.triangles.len()];
    for &t in &piece.triangles {
        match light_offset(c, t, light) {
            Some((d, distance)) if d.abs() > IN_PLANE * distance => {
                sides[t as usize] = if d > 0.0 {
                    LightSide::Front
                } else {
                    LightSide::Behind
                };
            }
            _ => {}
        }
    }
    sides
}

/// The same classification computed in f32 throughout, to find where single precision decides
/// differently (lights on or near a triangle's plane, far from the origin).
pub fn facing_flags_f32(
    group: &CasterGroup,
    component: usize,
    light: Vec3,
    epsilon: f32,
) -> Vec<bool> {
    let c = &group.connectivity;
    let pos = |i: u32| c.positions[i as usize];
    let mut facing = vec![false; c.triangles.len()];
    for &t in &group.components[component].triangles {
        let tri = c.triangles[t as usize];
        let n = (pos(tri[1]) - pos(tri[0])).cross(pos(tri[2]) - pos(tri[0]));
        if n == Vec3::ZERO || tri.iter().any(|&v| pos(v) == light) {
            continue;
        }
        let n = n.normalize();
        let centroid = (pos(tri[0]) + pos(tri[1]) + pos(tri[2])) / 3.0;
        let to_light = light - centroid;
        facing[t as usize] = n.dot(to_light) > -epsilon * to_light.length();
    }
    facing
}

/// Builds the volume of `component` of `group` for a point light at `light` (in the group's
/// space). `with_caps` adds the caps depth-fail needs.
pub fn build_volume(
    group: &CasterGroup,
    component: usize,
    light: DVec3,
    s: &VolumeSettings,
    with_caps: bool,
) -> VolumeMesh {
    build_volume_of(
        group,
        &group.components[component],
        light,
        s,
        with_caps,
        None,
    )
}

/// [`build_volume`] for any piece of the group (a component or a chunk): triangles outside the
/// piece count as not facing, so its cut edges close its volume.
pub fn build_volume_of(
    group: &CasterGroup,
    comp: &Component,
    light: DVec3,
    s: &VolumeSettings,
    with_caps: bool,
    cull: Option<ReceiverCull>,
) -> VolumeMesh {
    let c = &group.connectivity;
    let mut facing = facing_flags_of(group, comp, light, s.facing_epsilon);
    // Two-sided: the triangles facing away cast too, turned toward the light.
    let flipped: Option<Vec<bool>> = s.two_sided.then(|| {
        let sides = light_sides_of(group, comp, light);
        for &t in &comp.triangles {
            facing[t as usize] = sides[t as usize] != LightSide::InPlane;
        }
        sides
            .iter()
            .map(|&side| side == LightSide::Behind)
            .collect()
    });
    let (culled, scale) = match cull {
        Some(rc) => cull_to_receivers(c, comp, light, &rc, &mut facing),
        None => (0, f64::INFINITY),
    };
    let facing_list: Vec<u32> = comp
        .triangles
        .iter()
        .copied()
        .filter(|&t| facing[t as usize])
        .collect();
    let truncated = !facing_list.is_empty() && scale <= MAX_TRUNCATION;
    let mut mesh = VolumeMesh {
        facing: facing_list.len(),
        culled,
        truncated,
        ..VolumeMesh::default()
    };
    let sides = Sides {
        c,
        light,
        s,
        facing: &facing,
        flipped: flipped.as_deref(),
        far: if truncated { scale } else { f64::INFINITY },
    };
    for &ei in &comp.edges {
        sides.edge(&mut mesh, &c.edges[ei as usize]);
    }
    mesh.side_vertices = mesh.vertices.len();
    sides.caps(&mut mesh, &facing_list, with_caps);
    mesh.cap_vertices = mesh.vertices.len() - mesh.side_vertices;
    mesh
}

/// Leaves out of `facing` the facing triangles whose shadow reaches no receiver box near the
/// piece's shadow; returns how many, and one far cap scale for the whole piece (∞ unless
/// `truncate`): the largest any facing triangle needs, so that a light touching one keeps
/// the piece infinite. (A scale per triangle ends each prism sooner but adds a step side on
/// every inner edge: on oa_dm1 it doubled the triangles and cut only a sixth of the
/// fragments, a net loss on llvmpipe.)
fn cull_to_receivers(
    c: &Connectivity,
    comp: &Component,
    light: DVec3,
    rc: &ReceiverCull,
    facing: &mut [bool],
) -> (usize, f64) {
    let l = light.as_vec3();
    let piece_shadow = shadow_bounds(&comp.bounds, l, rc.radius);
    let near: Vec<&Aabb> = rc
        .boxes
        .iter()
        .filter(|b| b.intersects(&piece_shadow))
        .collect();
    let mut culled = 0;
    let mut scale = 1.0f64;
    for &t in &comp.triangles {
        if !facing[t as usize] {
            continue;
        }
        match shadow_reach(c, t as usize, l, rc.radius, &near) {
            None => {
                facing[t as usize] = false;
                culled += 1;
            }
            Some(reach) if rc.truncate => scale = scale.max(reach),
            Some(_) => scale = f64::INFINITY,
        }
    }
    if !rc.truncate {
        scale = f64::INFINITY;
    }
    (culled, scale)
}

/// Writes one piece's volume: the sides of its edges and its caps.
struct Sides<'a> {
    c: &'a Connectivity,
    light: DVec3,
    s: &'a VolumeSettings,
    facing: &'a [bool],
    /// Two-sided casting: the triangles cast with the opposite winding (they face away).
    flipped: Option<&'a [bool]>,
    /// How far every facing triangle's volume reaches (a scale about the light; ∞: to
    /// infinity, or the settings' finite distance).
    far: f64,
}

impl Sides<'_> {
    fn pos(&self, i: u32) -> DVec3 {
        self.c.positions[i as usize].as_dvec3()
    }

    /// The side of edge (a, b) from scale `from` (1: the edge itself) to scale `to`.
    fn quad(&self, a: u32, b: u32, from: f64, to: f64, mesh: &mut VolumeMesh) {
        let (light, s) = (self.light, self.s);
        // (b, a, a', b') faces out of the volume when (a, b) runs along the facing triangle's
        // counter-clockwise winding.
        let (pa, pb) = (self.pos(a), self.pos(b));
        let (ea, eb) = (extrude(pa, light, s, to), extrude(pb, light, s, to));
        let (va, vb) = (extrude(pa, light, s, from), extrude(pb, light, s, from));
        // The diagonal runs from the lower vertex index's point to the other's extrusion, so
        // that the two opposite quads of an edge between pieces (chunks) are the same triangles
        // and cancel pixel for pixel.
        let triangles = if a < b {
            [vb, va, eb, va, ea, eb]
        } else {
            [vb, va, ea, vb, ea, eb]
        };
        for v in triangles {
            mesh.vertices.push(to_f32(v));
        }
        mesh.quads += 1;
    }

    /// Triangle t's vertices in the winding it casts with.
    fn winding(&self, t: u32) -> [u32; 3] {
        let [a, b, c] = self.c.triangles[t as usize];
        match self.flipped {
            Some(f) if f[t as usize] => [c, b, a],
            _ => [a, b, c],
        }
    }

    /// The edge's direction in triangle t's winding.
    fn oriented(&self, t: u32, v: [u32; 2]) -> (u32, u32) {
        let tri = self.winding(t);
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if (a, b) == (v[0], v[1]) || (a, b) == (v[1], v[0]) {
                return (a, b);
            }
        }
        (v[0], v[1])
    }

    /// A facing triangle's side along edge `v`, from the edge to its reach.
    fn outer(&self, mesh: &mut VolumeMesh, t: u32, v: [u32; 2]) {
        let (a, b) = self.oriented(t, v);
        self.quad(a, b, 1.0, self.far, mesh);
    }

    /// The sides one edge contributes under the settings' edge rule.
    fn edge(&self, mesh: &mut VolumeMesh, e: &Edge) {
        let tris = self.c.triangles_of(e);
        let facing_here: Vec<u32> = tris
            .iter()
            .copied()
            .filter(|&t| self.facing[t as usize])
            .collect();
        // Turned triangles meet unturned ones running the same way along an edge: only the
        // signed rule counts both.
        let rule = if self.flipped.is_some() {
            EdgeRule::Signed
        } else {
            self.s.rule
        };
        match rule {
            // Two facing triangles on an edge that the rule treats as inner: their sides
            // cancel, since every facing triangle of a piece reaches equally far.
            EdgeRule::Paper if tris.len() == 2 && facing_here.len() == 2 => {}
            EdgeRule::Paper | EdgeRule::All => {
                for &t in &facing_here {
                    self.outer(mesh, t, e.v);
                }
            }
            EdgeRule::Signed => self.signed(mesh, e.v, &facing_here),
            EdgeRule::Manifold => {
                if tris.len() < 2 {
                    return;
                }
                let (f0, f1) = (self.facing[tris[0] as usize], self.facing[tris[1] as usize]);
                // Both facing: inner, their sides cancel (see above).
                if f0 != f1 {
                    self.outer(mesh, if f0 { tris[0] } else { tris[1] }, e.v);
                }
            }
        }
    }

    /// `EdgeRule::Signed`: +1 for each facing triangle running v[0] -> v[1], -1 for
    /// v[1] -> v[0], each from the edge to its own reach: between consecutive reaches the net
    /// of the triangles reaching further.
    fn signed(&self, mesh: &mut VolumeMesh, v: [u32; 2], facing_here: &[u32]) {
        let mut spans: Vec<(f64, i32)> = facing_here
            .iter()
            .map(|&t| {
                let sign = if self.oriented(t, v) == (v[0], v[1]) {
                    1
                } else {
                    -1
                };
                (self.far, sign)
            })
            .collect();
        spans.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut from = 1.0;
        for i in 0..spans.len() {
            let to = spans[i].0;
            let net: i32 = spans[i..].iter().map(|x| x.1).sum();
            if to > from && net != 0 {
                let (a, b) = if net > 0 { (v[0], v[1]) } else { (v[1], v[0]) };
                for _ in 0..net.unsigned_abs() {
                    self.quad(a, b, from, to, mesh);
                }
            }
            from = from.max(to);
        }
    }

    /// The front cap (the facing triangles, `with_caps`) and the back cap (extruded to the
    /// reach, flipped); a truncated volume's back cap closes it under depth-pass too.
    fn caps(&self, mesh: &mut VolumeMesh, facing_list: &[u32], with_caps: bool) {
        let tri = |t: u32| self.winding(t).map(|i| self.pos(i));
        if with_caps {
            for &t in facing_list {
                for p in tri(t) {
                    mesh.vertices.push(to_f32([p.x, p.y, p.z, 1.0]));
                }
            }
        }
        if with_caps || mesh.truncated {
            for &t in facing_list {
                let [a, b, c] = tri(t);
                // Flipped: the back cap faces away from the light, out of the volume.
                for p in [c, b, a] {
                    mesh.vertices
                        .push(to_f32(extrude(p, self.light, self.s, self.far)));
                }
            }
        }
    }
}

/// A group's transform to world space.
pub fn group_transform(scene: &Scene, owner: SurfaceOwner) -> Mat4 {
    match owner {
        SurfaceOwner::World => Mat4::IDENTITY,
        SurfaceOwner::Model(m) => scene.models[m].transform,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes::{MeshData, cuboid, sphere, torus};

    fn tris(m: &MeshData) -> Vec<[Vec3; 3]> {
        m.indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| m.vertices[t[k] as usize].pos()))
            .collect()
    }

    fn settings(rule: EdgeRule) -> VolumeSettings {
        VolumeSettings {
            rule,
            extrusion: Extrusion::Infinite,
            finite_distance: 1000.0,
            facing_epsilon: 0.0,
            two_sided: false,
        }
    }

    /// Every vertex of the extruded edges has even degree: the silhouette is closed loops.
    fn silhouette_is_closed(mesh: &VolumeMesh) -> bool {
        let mut degree = std::collections::HashMap::new();
        for q in mesh.vertices[..mesh.side_vertices].chunks_exact(6) {
            // Quad (b, a, a', b', ...): its edge is a-b.
            for v in [q[0], q[1]] {
                *degree.entry(v.map(f32::to_bits)).or_insert(0) += 1;
            }
        }
        degree.values().all(|d| d % 2 == 0)
    }

    #[test]
    fn closed_meshes_give_closed_silhouettes_and_finite_geometry() {
        let light = DVec3::new(3.0, 4.0, 12.0);
        for m in [
            cuboid(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 2.0, 3.0), 1.0),
            sphere(Vec3::new(0.5, 0.0, 2.0), 2.0, 24, 12),
            torus(Vec3::ZERO, 3.0, 1.0, 32, 16, 50.0),
        ] {
            let g = CasterGroup::build(SurfaceOwner::World, tris(&m));
            assert_eq!(g.components.len(), 1);
            let v = build_volume(&g, 0, light, &settings(EdgeRule::Paper), true);
            assert!(v.quads > 0 && v.facing > 0);
            assert!(silhouette_is_closed(&v), "open silhouette");
            assert!(v.vertices.iter().all(|p| p.iter().all(|x| x.is_finite())));
            assert_eq!(v.cap_vertices, 6 * v.facing);
            // On a closed 2-manifold the paper's rule and the manifold rule agree.
            let m2 = build_volume(&g, 0, light, &settings(EdgeRule::Manifold), true);
            assert_eq!(m2.quads, v.quads);
        }
    }

    #[test]
    fn a_cube_under_a_light_above_has_a_four_edge_silhouette() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let v = build_volume(
            &g,
            0,
            DVec3::new(0.0, 0.0, 10.0),
            &settings(EdgeRule::Paper),
            false,
        );
        // Only the top face (2 triangles) faces the light; its 4 outer edges extrude.
        assert_eq!((v.facing, v.quads), (2, 4));
        assert_eq!(v.cap_vertices, 0);
        let all = build_volume(
            &g,
            0,
            DVec3::new(0.0, 0.0, 10.0),
            &settings(EdgeRule::All),
            false,
        );
        assert_eq!(all.quads, 6, "extrude-all adds the diagonal twice");
    }

    #[test]
    fn open_and_non_manifold_edges_follow_each_rule() {
        // A quad (two triangles) facing up, plus a third triangle on its diagonal (a fin).
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        let fin = [a, c, Vec3::new(0.5, 0.5, 1.0)];
        let g = CasterGroup::build(SurfaceOwner::World, vec![[a, b, c], [a, c, d], fin]);
        let light = DVec3::new(0.3, 0.2, 10.0);
        let paper = build_volume(&g, 0, light, &settings(EdgeRule::Paper), false);
        let manifold = build_volume(&g, 0, light, &settings(EdgeRule::Manifold), false);
        // Paper: the 4 open outer edges, the diagonal once per facing triangle on it (3 triangles
        // there), and the fin's own open edges if it faces the light.
        assert!(paper.quads >= 4 + 2);
        // The naive rule never extrudes open edges: the outer boundary is missing.
        assert!(
            manifold.quads < 4,
            "manifold rule extruded {}",
            manifold.quads
        );
    }

    #[test]
    fn components_split_disconnected_casters_and_bound_them() {
        let mut t = tris(&cuboid(Vec3::ZERO, Vec3::ONE, 1.0));
        t.extend(tris(&cuboid(Vec3::splat(5.0), Vec3::splat(6.0), 1.0)));
        let g = CasterGroup::build(SurfaceOwner::World, t);
        assert_eq!(g.components.len(), 2);
        assert_eq!(g.components[1].bounds.min, Vec3::splat(5.0));
        let light = DVec3::new(3.0, 3.0, 20.0);
        let v0 = build_volume(&g, 0, light, &settings(EdgeRule::Paper), true);
        let v1 = build_volume(&g, 1, light, &settings(EdgeRule::Paper), true);
        assert!(v0.quads >= 4 && v1.quads >= 4);
    }

    #[test]
    fn the_near_plane_test_spots_views_inside_a_shadow() {
        let caster = Aabb {
            min: Vec3::new(-1.0, -1.0, 4.0),
            max: Vec3::new(1.0, 1.0, 5.0),
        };
        let light = Vec3::new(0.0, 0.0, 10.0);
        // Straight below the caster: inside its infinite shadow.
        assert!(potentially_inside_shadow(&caster, Vec3::ZERO, light, 0.1));
        // Off to the side: safe for depth-pass.
        assert!(!potentially_inside_shadow(
            &caster,
            Vec3::new(20.0, 0.0, 0.0),
            light,
            0.1
        ));
        // Near the caster, within the near-plane stretch.
        assert!(potentially_inside_shadow(
            &caster,
            Vec3::new(1.5, 0.0, 4.5),
            light,
            1.0
        ));
    }

    #[test]
    fn the_triangle_near_plane_test_is_conservative_and_finer_than_the_box() {
        // A 20x20 floor facing up at z = 5 and a cube on it; the light just above the floor.
        let mut t = vec![
            [
                Vec3::new(-10.0, -10.0, 5.0),
                Vec3::new(10.0, -10.0, 5.0),
                Vec3::new(10.0, 10.0, 5.0),
            ],
            [
                Vec3::new(-10.0, -10.0, 5.0),
                Vec3::new(10.0, 10.0, 5.0),
                Vec3::new(-10.0, 10.0, 5.0),
            ],
        ];
        t.extend(tris(&cuboid(
            Vec3::new(2.0, 2.0, 5.0),
            Vec3::new(3.0, 3.0, 6.0),
            1.0,
        )));
        let g = CasterGroup::build(SurfaceOwner::World, t);
        let piece = Component {
            triangles: (0..g.connectivity.triangles.len() as u32).collect(),
            edges: Vec::new(),
            bounds: g
                .components
                .iter()
                .fold(Aabb::EMPTY, |b, c| b.union(&c.bounds)),
            alpha_tested: false,
            open: false,
        };
        let light = DVec3::new(0.0, 0.0, 5.5);
        let near_test =
            |quad: &[DVec3; 4]| near_plane_shadowed(&g, &piece, light, quad, 0.0, false);
        let quad_at = |c: DVec3, half: f64| {
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, y)| c + DVec3::new(x * half, y * half, 0.0))
        };
        // Above the floor, beside the cube: the box test says depth-fail, the triangles say no
        // segment from the light to the near plane crosses a facing triangle.
        let open = quad_at(DVec3::new(-6.0, 0.0, 7.0), 0.1);
        assert!(potentially_inside_shadow(
            &piece.bounds,
            open[0].as_vec3(),
            light.as_vec3(),
            0.1
        ));
        assert!(!near_test(&open));
        // Below the floor, and behind the cube: in shadow.
        assert!(near_test(&quad_at(DVec3::new(0.0, 0.0, 2.0), 0.1)));
        assert!(near_test(&quad_at(DVec3::new(5.0, 5.0, 6.5), 0.1)));
        // A point (the eye, under depth clamping): the segment to the light alone.
        assert!(near_test(&[DVec3::new(0.0, 0.0, 2.0); 4]));
        assert!(!near_test(&[DVec3::new(-6.0, 0.0, 7.0); 4]));
        // Never false where a point of the rectangle is in shadow (random rectangles, points
        // on a grid over each, segments against every facing triangle).
        let facing = facing_flags_of(&g, &piece, light, 0.0);
        let crosses = |q: DVec3| {
            piece
                .triangles
                .iter()
                .filter(|&&t| facing[t as usize])
                .any(|&t| {
                    let [a, b, c] = g.connectivity.triangles[t as usize]
                        .map(|v| g.connectivity.positions[v as usize].as_dvec3());
                    segment_hits_triangle(light, q, a, b, c)
                })
        };
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut shadowed, mut refined) = (0, 0);
        for _ in 0..400 {
            let c = DVec3::new(rnd() * 24.0 - 12.0, rnd() * 24.0 - 12.0, rnd() * 6.0 + 2.0);
            let quad = quad_at(c, 0.05 + rnd() * 0.5);
            let any = (0..=4).any(|i| {
                (0..=4).any(|j| {
                    let (u, v) = (i as f64 / 4.0, j as f64 / 4.0);
                    crosses(quad[0].lerp(quad[1], u).lerp(quad[3].lerp(quad[2], u), v))
                })
            });
            let test = near_test(&quad);
            assert!(
                test || !any,
                "rectangle at {c} is in shadow but the test says not"
            );
            shadowed += any as usize;
            refined += (!test) as usize;
        }
        assert!(
            shadowed > 20 && refined > 100,
            "{shadowed} shadowed, {refined} refined"
        );
    }

    /// Whether the segment p→q crosses triangle abc (Möller–Trumbore, edges included).
    fn segment_hits_triangle(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
        let d = q - p;
        let (e1, e2) = (b - a, c - a);
        let h = d.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-12 {
            return false;
        }
        let s = (p - a) / det;
        let u = s.dot(h);
        let qv = s.cross(e1);
        let v = d.dot(qv);
        let t = e2.dot(qv);
        (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&t)
    }

    /// Generalised winding number of the closed triangle soup `vertices` (w = 1) at `p`: the
    /// signed solid angles of its triangles over 4π (Van Oosterom and Strackee).
    fn winding(vertices: &[[f32; 4]], p: DVec3) -> f64 {
        let mut total = 0.0;
        for t in vertices.chunks_exact(3) {
            let [a, b, c] =
                [t[0], t[1], t[2]].map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) - p);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let num = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            total += 2.0 * num.atan2(den);
        }
        total / (4.0 * std::f64::consts::PI)
    }

    #[test]
    fn a_truncated_volume_holds_exactly_the_shadowed_receiver_points() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let light = DVec3::new(0.3, 0.2, 10.0);
        let floor = Aabb {
            min: Vec3::new(-20.0, -20.0, -3.0),
            max: Vec3::new(20.0, 20.0, -2.0),
        };
        let cull = |truncate| {
            Some(ReceiverCull {
                boxes: std::slice::from_ref(&floor),
                radius: 100.0,
                truncate,
            })
        };
        let s = settings(EdgeRule::Paper);
        for with_caps in [false, true] {
            let v = build_volume_of(&g, &g.components[0], light, &s, with_caps, cull(true));
            assert!(v.truncated);
            let infinite = build_volume_of(&g, &g.components[0], light, &s, with_caps, cull(false));
            assert!(!infinite.truncated && infinite.quads == v.quads);
            // Finite everywhere, closed by a far cap even without the depth-fail caps, and the
            // far cap just below the floor box.
            assert!(v.vertices.iter().all(|p| p[3] == 1.0));
            let far = &v.vertices[v.vertices.len() - 3 * v.facing..];
            assert!(far.iter().all(|p| p[2] < -3.0 && p[2] > -6.0), "{far:?}");
            if !with_caps {
                assert_eq!(v.cap_vertices, 3 * v.facing);
                continue;
            }
            // A point of the floor box is inside the volume exactly when the cube hides the
            // light from it.
            let (mut inside, mut outside) = (0, 0);
            for i in 0..21 {
                for j in 0..21 {
                    let p = DVec3::new(-5.05 + 0.5 * i as f64, -5.05 + 0.5 * j as f64, -2.5);
                    let shadowed = (0..=1000).any(|k| {
                        let q = p + (light - p) * (k as f64 / 1000.0);
                        q.abs().max_element() <= 1.0
                    });
                    let w = winding(&v.vertices, p);
                    assert!(
                        (w.abs() - if shadowed { 1.0 } else { 0.0 }).abs() < 1e-6,
                        "{p} {w}"
                    );
                    if shadowed {
                        inside += 1;
                    } else {
                        outside += 1;
                    }
                }
            }
            assert!(inside > 20 && outside > 20, "{inside} {outside}");
        }
    }

    #[test]
    fn a_piece_split_in_two_holds_what_the_whole_holds() {
        // A slab of sixteen boxes welded into one component under a light.
        let mut t = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = (i as f32 - 2.0, j as f32 - 2.0);
                t.extend(tris(&cuboid(
                    Vec3::new(x, y, 0.0),
                    Vec3::new(x + 1.0, y + 1.0, 0.5),
                    1.0,
                )));
            }
        }
        let g = CasterGroup::build(SurfaceOwner::World, t);
        let light = DVec3::new(0.2, 0.1, 6.0);
        // Finite and capped: every part is a closed mesh of finite points.
        let mut s = settings(EdgeRule::Signed);
        s.extrusion = Extrusion::Finite;
        s.finite_distance = 20.0;
        let (mut inside, mut checked) = (0, 0);
        for c in &g.components {
            // Every other triangle on one side of the cut.
            let a = g.subset(c, |tri| tri % 2 == 0);
            let b = g.subset(c, |tri| tri % 2 == 1);
            assert_eq!(a.triangles.len() + b.triangles.len(), c.triangles.len());
            assert!(a.edges.len() < c.edges.len() && b.edges.len() < c.edges.len());
            let mesh = |piece: &Component| build_volume_of(&g, piece, light, &s, true, None);
            let (whole, ma, mb) = (mesh(c), mesh(&a), mesh(&b));
            assert!(ma.facing > 0 && mb.facing > 0);
            // The parts' winding numbers add up to the whole's everywhere (points off the
            // slab's faces, in and out of its shadow).
            for i in 0..9 {
                for j in 0..9 {
                    let p = DVec3::new(-3.93 + i as f64, -3.87 + j as f64, -1.3 - 0.1 * j as f64);
                    let w = winding(&whole.vertices, p);
                    let sum = winding(&ma.vertices, p) + winding(&mb.vertices, p);
                    assert!((w - sum).abs() < 1e-6, "{p}: {w} against {sum}");
                    inside += (w.abs() > 0.5) as usize;
                    checked += 1;
                }
            }
        }
        assert!(inside > 10 && inside < checked, "{inside} of {checked}");
    }

    #[test]
    fn finite_extrusion_ends_at_its_distance() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let mut s = settings(EdgeRule::Paper);
        s.extrusion = Extrusion::Finite;
        s.finite_distance = 50.0;
        let light = DVec3::new(0.0, 0.0, 10.0);
        let v = build_volume(&g, 0, light, &s, true);
        for p in &v.vertices {
            assert_eq!(p[3], 1.0);
            let d = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64).distance(light);
            assert!(d < 62.0, "{d}");
        }
    }

    /// Two quads side by side in one plane, one facing the light and one (one-sided) facing
    /// away: an open surface seen from behind in part.
    fn half_turned_floor() -> CasterGroup {
        let (a, b, c, d) = (
            Vec3::new(-2.0, -1.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-2.0, 1.0, 0.0),
        );
        let (e, f) = (Vec3::new(2.0, -1.0, 0.0), Vec3::new(2.0, 1.0, 0.0));
        let up = [[a, b, c], [a, c, d]];
        let down = [[b, f, e], [b, c, f]];
        CasterGroup::build(SurfaceOwner::World, up.into_iter().chain(down).collect())
    }

    #[test]
    fn two_sided_casting_shadows_what_any_face_hides_and_one_sided_loses_the_turned_half() {
        let g = half_turned_floor();
        let light = DVec3::new(0.3, 0.2, 10.0);
        let s = VolumeSettings {
            extrusion: Extrusion::Finite,
            finite_distance: 100.0,
            ..settings(EdgeRule::Paper)
        };
        let grid = || {
            (0..25).flat_map(|i| {
                (0..13)
                    .map(move |j| DVec3::new(-6.05 + 0.5 * i as f64, -3.05 + 0.5 * j as f64, -3.0))
            })
        };
        // Hidden from the light by either quad (the reference counts every face as solid).
        let hidden = |p: DVec3| {
            let t = p.z / (p.z - light.z);
            let q = p + (light - p) * t;
            q.x.abs() <= 2.0 && q.y.abs() <= 1.0
        };
        let count = |two_sided: bool| {
            let s = VolumeSettings { two_sided, ..s };
            let v = build_volume_of(&g, &g.components[0], light, &s, true, None);
            let windings: Vec<(DVec3, f64)> =
                grid().map(|p| (p, winding(&v.vertices, p))).collect();
            // Closed and wound one way: every count 0 or the same ±1 (a count of the other
            // sign would cancel in the stencil, or saturate at 0 and light the point).
            let sign = windings
                .iter()
                .map(|w| w.1)
                .find(|w| w.abs() > 0.5)
                .unwrap_or(1.0);
            for &(p, w) in &windings {
                assert!(
                    w.abs() < 1e-6 || (w - sign.signum()).abs() < 1e-6,
                    "{p} {w}"
                );
            }
            windings
                .iter()
                .filter(|(p, w)| (w.abs() > 0.5) != hidden(*p))
                .count()
        };
        let hidden_points = grid().filter(|&p| hidden(p)).count();
        assert!(hidden_points > 40, "{hidden_points}");
        assert_eq!(count(true), 0);
        // One-sided (the paper): the turned half casts nothing.
        assert!(count(false) * 3 > hidden_points, "{}", count(false));
    }

    #[test]
    fn a_light_on_a_cubes_vertex_or_edge_keeps_the_cubes_whole_shadow_when_casting_two_sided() {
        let g = CasterGroup::build(
            SurfaceOwner::World,
            tris(&cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0)),
        );
        let s = VolumeSettings {
            two_sided: true,
            // The winding test reads positions, not points at infinity.
            extrusion: Extrusion::Finite,
            finite_distance: 100.0,
            ..settings(EdgeRule::Signed)
        };
        // Hidden: the segment to the light passes through the cube's inside.
        let hidden = |p: DVec3, light: DVec3| {
            (1..200).any(|k| {
                let q = p + (light - p) * (k as f64 / 200.0);
                q.abs().max_element() < 1.0 - 1e-6
            })
        };
        for light in [DVec3::new(1.0, 1.0, 1.0), DVec3::new(0.0, 1.0, 1.0)] {
            let sides = light_sides_of(&g, &g.components[0], light);
            let in_plane = sides.iter().filter(|&&x| x == LightSide::InPlane).count();
            assert_eq!(in_plane, if light.x == 0.0 { 4 } else { 6 }, "{light}");
            assert!(sides.iter().all(|&x| x != LightSide::Front));
            let v = build_volume_of(&g, &g.components[0], light, &s, true, None);
            let mut wrong = 0;
            let mut shadowed = 0;
            for i in 0..21 {
                for j in 0..21 {
                    // A floor under the cube, off its planes and the light's.
                    let p = DVec3::new(-5.03 + 0.5 * i as f64, -5.07 + 0.5 * j as f64, -4.0);
                    let inside = winding(&v.vertices, p).abs() > 0.5;
                    shadowed += inside as usize;
                    wrong += (inside != hidden(p, light)) as usize;
                }
            }
            assert!(shadowed > 50, "{light}: {shadowed}");
            assert_eq!(wrong, 0, "{light}");
        }
    }
}
