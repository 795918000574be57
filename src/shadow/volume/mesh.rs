//! Writing a piece's volume for one light: the settings, the mesh, and the side quads and caps
//! of its edges and facing triangles.

use super::reach::{MAX_TRUNCATION, cull_to_receivers};
use super::{
    CasterGroup, Component, EdgeRule, Extrusion, LightSide, ReceiverCull, facing_flags_of,
    light_sides_of,
};
use crate::shadow::edges::{Connectivity, Edge};
use glam::DVec3;

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
    /// Side quads (two triangles each), then back-cap triangles, then front-cap triangles.
    pub vertices: Vec<[f32; 4]>,
    /// Facing triangles left out because their shadow reaches no receiver.
    pub culled: usize,
    pub side_vertices: usize,
    /// Both caps' vertices, and the back cap's alone (first after the sides).
    pub cap_vertices: usize,
    pub back_cap_vertices: usize,
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

    /// The back cap (extruded to the reach, flipped; `with_caps`, or a truncated volume's,
    /// which closes it under depth-pass too), then the front cap (the facing triangles,
    /// `with_caps`): what depth-pass draws is the mesh up to the front cap, so one mesh built
    /// with caps serves either counting.
    fn caps(&self, mesh: &mut VolumeMesh, facing_list: &[u32], with_caps: bool) {
        let tri = |t: u32| self.winding(t).map(|i| self.pos(i));
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
        mesh.back_cap_vertices = mesh.vertices.len() - mesh.side_vertices;
        if with_caps {
            for &t in facing_list {
                for p in tri(t) {
                    mesh.vertices.push(to_f32([p.x, p.y, p.z, 1.0]));
                }
            }
        }
    }
}
