//! The recursive MIS quantities of vertex connection and merging (Georgiev 2012, "Implementing
//! vertex connection and merging", sections 3-5; the same quantities as SmallVCM's `dVCM`,
//! `dVC`, `dVM`). Each subpath carries three running sums from which the weight of any
//! technique that ends at its last vertex follows in O(1): a connection (s, t) of a light and
//! a camera vertex, a light vertex joined to the camera (t = 1), next-event estimation
//! (s = 1), a camera path that finds a light (s = 0), and a merge of a camera vertex with the
//! light vertices within the pass's radius.
//!
//! Densities are written as the report does: `pdf_w` per solid angle, `pdf_a` per area. The
//! heuristic is Veach's power heuristic with exponent `beta` (1: the balance heuristic); it
//! enters as `mis(x) = x^beta`, which is multiplicative, so every factor is raised on its own.
//! Merging competes with connections through eta_VCM = pi r^2 N_L (report, eq. 20): the merge
//! of a light subpath of N_L per pass stands in for a connection whose last edge is sampled
//! within the disc of radius r.
//!
//! Russian roulette is left out of every density, as in `bdpt`: the weights stay a partition
//! of unity over the techniques of each path, which is all unbiasedness asks of them.

/// How techniques are weighted and which are on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MisWeights {
    /// Exponent of the power heuristic (1: balance).
    pub beta: f32,
    /// mis(eta_VCM) when merges are on, else 0: the weight factor of a merge against a
    /// connection.
    pub vm_factor: f32,
    /// mis(1 / eta_VCM) when connections are on, else 0.
    pub vc_factor: f32,
    /// Weight factor of the light-tracing technique: mis(N_pixels / N_L) (1 with one light
    /// subpath per pixel), since camera paths sample one pixel each.
    pub light_trace_factor: f32,
}

impl MisWeights {
    /// The factors of a pass that merges within `radius` among `light_paths` light subpaths
    /// for `pixels` camera subpaths.
    pub fn new(
        beta: f32,
        radius: f32,
        light_paths: f32,
        pixels: f32,
        connections: bool,
        merges: bool,
    ) -> MisWeights {
        let eta = std::f32::consts::PI * radius * radius * light_paths;
        let mis = |x: f32| x.powf(beta);
        MisWeights {
            beta,
            vm_factor: if merges { mis(eta) } else { 0.0 },
            vc_factor: if connections && eta > 0.0 {
                mis(1.0 / eta)
            } else {
                0.0
            },
            light_trace_factor: mis(pixels / light_paths),
        }
    }

    #[inline]
    pub fn mis(&self, x: f32) -> f32 {
        if self.beta == 1.0 {
            x
        } else {
            x.powf(self.beta)
        }
    }
}

/// The running quantities of a subpath at its last vertex (report, section 5): with
/// p_i the density with which the subpath sampled vertex i and p_i^rev the density with which
/// the other subpath would have,
/// d_vcm ~ 1 / p_last, d_vc and d_vm ~ the sums over the techniques that would have sampled
/// more of this subpath from the other side (connections and merges), each scaled by the
/// reverse densities they need.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubpathMis {
    pub d_vcm: f32,
    pub d_vc: f32,
    pub d_vm: f32,
}

impl SubpathMis {
    /// A light subpath leaving its light (report, eqs. 31-33, delta lights 48-50): `direct_pdf_a` is the density
    /// with which next-event estimation picks this origin (per area, or per solid angle for
    /// infinite lights; 1 for a delta position), `emission_pdf_w` the density of the origin
    /// and direction together, `cos_light` the cosine at a finite light's surface (1 for
    /// points and infinite lights). A delta light cannot be connected to: d_vc = d_vm = 0.
    pub fn light_start(
        w: &MisWeights,
        direct_pdf_a: f32,
        emission_pdf_w: f32,
        cos_light: f32,
        delta_light: bool,
    ) -> SubpathMis {
        let d_vc = if delta_light {
            0.0
        } else {
            w.mis(cos_light / emission_pdf_w)
        };
        SubpathMis {
            d_vcm: w.mis(direct_pdf_a / emission_pdf_w),
            d_vc,
            d_vm: d_vc * w.vc_factor,
        }
    }

    /// A camera subpath at its first vertex: d_vcm = N_L / (N_pixels p_A(x_1)) with p_A the
    /// area density of the camera ray meeting x_1 (report, eq. 31 with its distance and
    /// cosine applied, which `arrive` would apply), which holds for the orthographic camera too.
    pub fn camera_first_hit(w: &MisWeights, first_hit_pdf_a: f32) -> SubpathMis {
        SubpathMis {
            d_vcm: w.mis(1.0 / first_hit_pdf_a) / w.light_trace_factor,
            d_vc: 0.0,
            d_vm: 0.0,
        }
    }

    /// Arriving at a surface (report, eqs. 31-36, their distance and cosine): the last edge's solid-angle density becomes
    /// one per area at the new vertex. `dist_sq` is None for the first edge from an infinite
    /// light, whose origin density is already per area of the disc across the scene.
    pub fn arrive(&mut self, w: &MisWeights, dist_sq: Option<f32>, cos_here: f32) {
        if let Some(d2) = dist_sq {
            self.d_vcm *= w.mis(d2);
        }
        let c = w.mis(cos_here.abs());
        self.d_vcm /= c;
        self.d_vc /= c;
        self.d_vm /= c;
    }

    /// Scattering on (report, eqs. 34-36; a delta lobe 53-55): `pdf_w` the density of the direction sampled,
    /// `rev_pdf_w` that of sampling the arrival direction back from it, `cos_out` the
    /// cosine of the new direction at this vertex. A delta lobe samples no technique of its
    /// own and its densities cancel: only the cosine remains.
    pub fn scatter(
        &mut self,
        w: &MisWeights,
        pdf_w: f32,
        rev_pdf_w: f32,
        cos_out: f32,
        delta: bool,
    ) {
        let cos_out = cos_out.abs();
        if delta {
            self.d_vcm = 0.0;
            self.d_vc *= w.mis(cos_out);
            self.d_vm *= w.mis(cos_out);
            return;
        }
        let g = w.mis(cos_out / pdf_w);
        let d_vc = g * (self.d_vc * w.mis(rev_pdf_w) + self.d_vcm + w.vm_factor);
        let d_vm = g * (self.d_vm * w.mis(rev_pdf_w) + self.d_vcm * w.vc_factor + 1.0);
        self.d_vc = d_vc;
        self.d_vm = d_vm;
        self.d_vcm = w.mis(1.0 / pdf_w);
    }
}

/// Weight of a camera subpath that finds a light (s = 0; report, eqs. 42-43 in 37): `direct_pdf_a`
/// is the density with which next-event estimation would pick the point (per solid angle for
/// the environment), `emission_pdf_w` that with which a light subpath would leave it towards
/// the camera path, both with the light's selection probability.
pub fn weight_emission_hit(
    w: &MisWeights,
    camera: &SubpathMis,
    direct_pdf_a: f32,
    emission_pdf_w: f32,
) -> f32 {
    let w_camera = w.mis(direct_pdf_a) * camera.d_vcm + w.mis(emission_pdf_w) * camera.d_vc;
    1.0 / (1.0 + w_camera)
}

/// Weight of next-event estimation (s = 1; report, eqs. 44-45 in 37). `bsdf_pdf_w` is the camera
/// vertex's density of sampling the direction to the light (0 for a delta light),
/// `bsdf_rev_pdf_w` the reverse, `direct_pdf_w` next-event estimation's solid-angle density
/// (with the selection probability), `emission_pdf_w` the light's density of emitting
/// towards the camera vertex, `cos_to_light` and `cos_at_light` the geometric cosines at
/// either end.
#[allow(clippy::too_many_arguments)]
pub fn weight_next_event(
    w: &MisWeights,
    camera: &SubpathMis,
    bsdf_pdf_w: f32,
    bsdf_rev_pdf_w: f32,
    direct_pdf_w: f32,
    emission_pdf_w: f32,
    cos_to_light: f32,
    cos_at_light: f32,
) -> f32 {
    let w_light = w.mis(bsdf_pdf_w / direct_pdf_w);
    let w_camera = w.mis(emission_pdf_w * cos_to_light / (direct_pdf_w * cos_at_light))
        * (w.vm_factor + camera.d_vcm + camera.d_vc * w.mis(bsdf_rev_pdf_w));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of a light vertex joined to the camera (t = 1; report, eqs. 46-47 in 37): `camera_pdf_a` is
/// the area density with which a camera ray meets the light vertex, `bsdf_rev_pdf_w` the
/// light vertex's density of sampling its arrival direction from the camera's.
pub fn weight_light_trace(
    w: &MisWeights,
    light: &SubpathMis,
    camera_pdf_a: f32,
    bsdf_rev_pdf_w: f32,
) -> f32 {
    let w_light = w.mis(camera_pdf_a)
        * w.light_trace_factor
        * (w.vm_factor + light.d_vcm + light.d_vc * w.mis(bsdf_rev_pdf_w));
    1.0 / (w_light + 1.0)
}

/// Weight of a connection of a light and a camera vertex (report, eqs. 40-41 in 37): the densities
/// per area with which each vertex's BSDF would have sampled the other vertex, and per solid
/// angle the reverse densities at each.
pub fn weight_connection(
    w: &MisWeights,
    light: &SubpathMis,
    camera: &SubpathMis,
    (camera_pdf_a, camera_rev_pdf_w): (f32, f32),
    (light_pdf_a, light_rev_pdf_w): (f32, f32),
) -> f32 {
    let w_light =
        w.mis(camera_pdf_a) * (w.vm_factor + light.d_vcm + light.d_vc * w.mis(light_rev_pdf_w));
    let w_camera =
        w.mis(light_pdf_a) * (w.vm_factor + camera.d_vcm + camera.d_vc * w.mis(camera_rev_pdf_w));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of a merge of a camera vertex with a light vertex (report, eqs. 38-39 in 37):
/// `camera_pdf_w` is the camera vertex's density of continuing along the light vertex's
/// arrival direction, `camera_rev_pdf_w` the reverse.
pub fn weight_merge(
    w: &MisWeights,
    light: &SubpathMis,
    camera: &SubpathMis,
    camera_pdf_w: f32,
    camera_rev_pdf_w: f32,
) -> f32 {
    let w_light = light.d_vcm * w.vc_factor + light.d_vm * w.mis(camera_pdf_w);
    let w_camera = camera.d_vcm * w.vc_factor + camera.d_vm * w.mis(camera_rev_pdf_w);
    1.0 / (w_light + 1.0 + w_camera)
}
