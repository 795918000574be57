//! Building caster groups: welding an owner's casting triangles, splitting them into connected
//! components and those into chunks, and rebuilding the groups of models that moved.

use super::{CasterGroup, CasterGroups, ChunkNode, Component, PieceRef};
use crate::geometry::Aabb;
use crate::scene::{Scene, SurfaceOwner};
use crate::shadow::edges::Connectivity;
use glam::Vec3;

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
                .map(|o| std::sync::Arc::new(CasterGroup::of_owner(scene, o)))
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
                    std::sync::Arc::new(CasterGroup::of_owner(scene, g.owner))
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
