//! Published reference values of the lid-driven cavity (lid moving in +x on the unit square,
//! ψ < 0 in the primary vortex) and the comparison of a computed velocity with them: the
//! centreline tables of Ghia, Ghia & Shin (Re = 100, 400) and of Botella & Peyret (Re = 1000),
//! and Botella & Peyret's primary-vortex minimum ψ_min.

// Ghia, Ghia & Shin, J. Comput. Phys. 48 (1982) 387–411, Table I (u on x = 0.5) and Table II
// (v on y = 0.5), Re = 100 and 400, lid moving in +x.
pub const GHIA_Y: [f64; 17] = [
    0.0, 0.0547, 0.0625, 0.0703, 0.1016, 0.1719, 0.2813, 0.4531, 0.5, 0.6172, 0.7344, 0.8516,
    0.9531, 0.9609, 0.9688, 0.9766, 1.0,
];
pub const GHIA_U100: [f64; 17] = [
    0.0, -0.03717, -0.04192, -0.04775, -0.06434, -0.10150, -0.15662, -0.21090, -0.20581, -0.13641,
    0.00332, 0.23151, 0.68717, 0.73722, 0.78871, 0.84123, 1.0,
];
pub const GHIA_U400: [f64; 17] = [
    0.0, -0.08186, -0.09266, -0.10338, -0.14612, -0.24299, -0.32726, -0.17119, -0.11477, 0.02135,
    0.16256, 0.29093, 0.55892, 0.61756, 0.68439, 0.75837, 1.0,
];
pub const GHIA_X: [f64; 17] = [
    0.0, 0.0625, 0.0703, 0.0781, 0.0938, 0.1563, 0.2266, 0.2344, 0.5, 0.8047, 0.8594, 0.9063,
    0.9453, 0.9531, 0.9609, 0.9688, 1.0,
];
pub const GHIA_V100: [f64; 17] = [
    0.0, 0.09233, 0.10091, 0.10890, 0.12317, 0.16077, 0.17507, 0.17527, 0.05454, -0.24533,
    -0.22445, -0.16914, -0.10313, -0.08864, -0.07391, -0.05906, 0.0,
];
pub const GHIA_V400: [f64; 17] = [
    0.0, 0.18360, 0.19713, 0.20920, 0.22965, 0.28124, 0.30203, 0.30174, 0.05186, -0.38598,
    -0.44993, -0.23827, -0.22847, -0.19254, -0.15663, -0.12146, 0.0,
];

/// The Ghia Re = 400 v station x = 0.9063 (index 11): the tabulated −0.23827 breaks the profile
/// between −0.44993 (x = 0.8594) and −0.22847 (x = 0.9453); it is a misprint and is left out.
pub const GHIA_V400_MISPRINT: usize = 11;

// Botella & Peyret, Comput. Fluids 27 (1998) 421–433, Re = 1000 (Chebyshev collocation, N = 160),
// centreline tables and primary vortex, in the orientation used here (lid moving in +x, as in
// Ghia et al.): their vortex centre x = 0.4692 is measured in the mirrored orientation, here
// x = 1 − 0.4692 = 0.5308 (public validation data quote the tables in this orientation with the
// vortex at (0.53079, 0.56524), ψ = −0.118936603; the computed centre agrees). u on x = 0.5:
pub const BP_Y: [f64; 15] = [
    0.0547, 0.0625, 0.0703, 0.1016, 0.1719, 0.2813, 0.4531, 0.5, 0.6172, 0.7344, 0.8516, 0.9531,
    0.9609, 0.9688, 0.9766,
];
pub const BP_U: [f64; 15] = [
    -0.1812881, -0.2023300, -0.2228955, -0.3004561, -0.3885690, -0.2803696, -0.1081999, -0.0620561,
    0.0570178, 0.1886747, 0.3372212, 0.4723329, 0.5169277, 0.5808359, 0.6644227,
];
// v on y = 0.5:
pub const BP_X: [f64; 15] = [
    0.0625, 0.0703, 0.0781, 0.0938, 0.1563, 0.2266, 0.2344, 0.5, 0.8047, 0.8594, 0.9063, 0.9453,
    0.9531, 0.9609, 0.9688,
];
pub const BP_V: [f64; 15] = [
    0.2807056, 0.2962703, 0.3099097, 0.3330442, 0.3769189, 0.3339924, 0.3253592, 0.0257995,
    -0.3202137, -0.4264545, -0.5264392, -0.4103754, -0.3553213, -0.2936869, -0.2279225,
];
/// ψ_min (its location, mirrored to the +x lid, is x = 1 − 0.4692, y = 0.5652).
pub const BP_PSI_MIN: f64 = -0.1189366;

/// Stream-function contour levels of Ghia et al. (Table III), used for the cavity pictures.
pub const GHIA_PSI_LEVELS: [f64; 24] = [
    -0.1175, -0.115, -0.11, -0.1, -0.09, -0.07, -0.05, -0.03, -0.01, -1e-4, -1e-5, -1e-7, -1e-10,
    1e-8, 1e-7, 1e-6, 1e-5, 5e-5, 1e-4, 2.5e-4, 5e-4, 1e-3, 1.5e-3, 3e-3,
];

/// The tables of one Reynolds number: u(0.5, y) at `ys`, v(x, 0.5) at `xs`, the v stations
/// left out, and ψ_min where published.
#[derive(Clone, Copy, Debug)]
pub struct CentrelineTable {
    /// "Ghia et al. (1982)" or "Botella & Peyret (1998)".
    pub source: &'static str,
    pub ys: &'static [f64],
    pub us: &'static [f64],
    pub xs: &'static [f64],
    pub vs: &'static [f64],
    pub skip_v: &'static [usize],
    pub psi_min: Option<f64>,
}

/// The reference of Reynolds number `re` (100, 400: Ghia et al.; 1000: Botella & Peyret).
pub fn table(re: f64) -> Option<CentrelineTable> {
    if re == 100.0 {
        Some(CentrelineTable {
            source: "Ghia et al. (1982)",
            ys: &GHIA_Y,
            us: &GHIA_U100,
            xs: &GHIA_X,
            vs: &GHIA_V100,
            skip_v: &[],
            psi_min: None,
        })
    } else if re == 400.0 {
        Some(CentrelineTable {
            source: "Ghia et al. (1982)",
            ys: &GHIA_Y,
            us: &GHIA_U400,
            xs: &GHIA_X,
            vs: &GHIA_V400,
            skip_v: &[GHIA_V400_MISPRINT],
            psi_min: None,
        })
    } else if re == 1000.0 {
        Some(CentrelineTable {
            source: "Botella & Peyret (1998)",
            ys: &BP_Y,
            us: &BP_U,
            xs: &BP_X,
            vs: &BP_V,
            skip_v: &[],
            psi_min: Some(BP_PSI_MIN),
        })
    } else {
        None
    }
}

impl CentrelineTable {
    /// Largest |u − u_ref| over the u stations and |v − v_ref| over the v stations of the
    /// computed `velocity(x)` (None outside the domain: the station is skipped).
    pub fn deviations(&self, velocity: &dyn Fn([f64; 2]) -> Option<[f64; 2]>) -> (f64, f64) {
        let mut eu = 0.0f64;
        for (&y, &u) in self.ys.iter().zip(self.us) {
            if let Some(v) = velocity([0.5, y]) {
                eu = eu.max((v[0] - u).abs());
            }
        }
        let mut ev = 0.0f64;
        for (i, (&x, &v)) in self.xs.iter().zip(self.vs).enumerate() {
            if self.skip_v.contains(&i) {
                continue;
            }
            if let Some(w) = velocity([x, 0.5]) {
                ev = ev.max((w[1] - v).abs());
            }
        }
        (eu, ev)
    }
}
