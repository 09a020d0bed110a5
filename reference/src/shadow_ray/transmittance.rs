//! The shadow ray's transmittance: crossings counted even-odd from the light's end, media
//! integrated per unit depth (closed form for constant ones, marched through detail), thin
//! shells one reference length each.

use super::geometry::{Start, intersect};
use super::{OPAQUE_DEPTH, Reference, Scratch};
use convshadow_cpu::shading::detail_value;

use super::geometry::to_detail_f64;

impl Reference<'_> {
    /// Transmittance per channel from point `p` (grid px x, y; relative depth z) along
    /// `q(u) = p + u·d`, u ∈ (0, `u_end`], to where the light is outside every mesh (a
    /// directional light's ray `d = (dir, −1)` to depth 0, in front of every vertex; a point
    /// light's `d = P − p` to the light, `u_end = 1`): the product over the media the ray
    /// crosses. Media attenuate per unit depth, `|d_z|` per unit of u.
    pub(super) fn transmittance(
        &self,
        p: [f64; 3],
        d: [f64; 3],
        u_end: f64,
        start: Start,
        scratch: &mut Scratch,
    ) -> [f64; 3] {
        let end = [p[0] + u_end * d[0], p[1] + u_end * d[1]];
        self.candidates([p[0], p[1]], end, &mut scratch.tris);
        scratch.hits.clear();
        // The surface the ray starts on is not crossed (`start.skip`), and crossings closer than
        // `start.tol` are the same surface met again through rounding (a neighbouring triangle
        // at a shared edge, a coincident face): see [`Start`].
        let tol = start.tol;
        for &i in &scratch.tris {
            if i == start.skip {
                continue;
            }
            let t = &self.tris[i as usize];
            if let Some(u) = intersect(p, d, t)
                && u > tol
                && u < u_end + tol
            {
                scratch.hits.push((u, t.mesh));
            }
        }
        // From the light side (largest u) towards p, toggling inside bits.
        scratch
            .hits
            .sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut inside = 0u32;
        let mut optical = [0.0f64; 3];
        for k in 0..scratch.hits.len() {
            if optical.iter().all(|&o| o > OPAQUE_DEPTH) {
                // Transmittance below e^-40 (4e-18) on every channel: nothing measurable is left.
                return [0.0; 3];
            }
            let (u_far, mesh) = scratch.hits[k];
            if self.geometry.raster.parity_meshes & (1 << mesh) == 0 {
                // An open mesh is a thin shell: one slab of its material at the crossing.
                self.cross_shell(&mut optical, p, d, mesh as usize, u_far);
            } else {
                inside ^= 1 << mesh;
            }
            let u_near = if k + 1 < scratch.hits.len() {
                scratch.hits[k + 1].0
            } else {
                0.0
            };
            if inside == 0 || u_far <= u_near {
                continue;
            }
            let mesh = inside.trailing_zeros() as usize;
            let m = self.mesh_material[mesh];
            let od = self.optical_depth(p, d, mesh, m, u_near, u_far);
            let tau = self.media[m].transport;
            for (o, t) in optical.iter_mut().zip(tau) {
                // Transport 1 lets the channel through whatever the optical depth (also ∞).
                if t < 1.0 {
                    *o += od * (1.0 - t);
                }
            }
        }
        optical.map(|o| (-o).exp())
    }

    /// Adds to `optical` (per channel) the crossing at `u` of the ray from `p` through the thin
    /// shell `mesh` (an open mesh, docs/scene-format.md "Open meshes"): one reference length of
    /// its material at the crossing's detail value, `1 − α·(1 − τ)` with `α = 1 − e^(−κ·e_ref)`,
    /// the material's opacity there.
    fn cross_shell(&self, optical: &mut [f64; 3], p: [f64; 3], d: [f64; 3], mesh: usize, u: f64) {
        let medium = &self.media[self.mesh_material[mesh]];
        let kappa = if self.is_constant(mesh) {
            medium.kappa(0.0)
        } else {
            self.kappa_at(mesh, [p[0] + u * d[0], p[1] + u * d[1], p[2] + u * d[2]])
        };
        let alpha = -(-kappa * medium.reference_length).exp_m1();
        for (o, t) in optical.iter_mut().zip(medium.transport) {
            if t < 1.0 {
                // −ln(1 − α(1 − τ)): infinite where the shell takes out all of the channel.
                *o -= (-alpha * (1.0 - t)).ln_1p();
            }
        }
    }

    /// Whether mesh `mesh`'s medium is the same everywhere (no gradient, or no detail to read
    /// it at): its κ is `kappa(0)`.
    fn is_constant(&self, mesh: usize) -> bool {
        let material = &self.plan.materials[self.plan.mesh_material[mesh] as usize];
        self.media[self.mesh_material[mesh]].stops.is_empty()
            || (material.detail.is_none() && material.texture.is_none())
    }

    /// κ of mesh `mesh`'s medium at point `q` (grid px x, y; relative depth z): its detail
    /// value there through the gradient.
    fn kappa_at(&self, mesh: usize, q: [f64; 3]) -> f64 {
        let material = &self.plan.materials[self.plan.mesh_material[mesh] as usize];
        let v = detail_value(material, to_detail_f64(&self.plan.mesh_to_detail[mesh], q));
        self.media[self.mesh_material[mesh]].kappa(f64::from(v))
    }

    /// ∫κ·|dz| over u ∈ [u0, u1] of the ray `p + u·d` in mesh `mesh` of material `m` (per unit
    /// depth; an opaque medium blocks any positive length, also one along the slab planes).
    #[allow(clippy::too_many_arguments)]
    fn optical_depth(
        &self,
        p: [f64; 3],
        d: [f64; 3],
        mesh: usize,
        m: usize,
        u0: f64,
        u1: f64,
    ) -> f64 {
        let len = (u1 - u0) * d[2].abs();
        if self.is_constant(mesh) {
            let k = self.media[m].kappa(0.0);
            return if k.is_infinite() { k } else { k * len };
        }
        let n = (len / self.step).ceil().max(1.0) as usize;
        let h = (u1 - u0) / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            let u = u0 + (i as f64 + 0.5) * h;
            sum += self.kappa_at(mesh, [p[0] + u * d[0], p[1] + u * d[1], p[2] + u * d[2]]);
            if sum.is_infinite() {
                return sum;
            }
        }
        sum * h * d[2].abs()
    }
}
