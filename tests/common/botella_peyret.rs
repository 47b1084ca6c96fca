// Reference tables shared by tests/cavity.rs and tools/cavity_refinement.rs (included, not a
// module).

// Botella & Peyret, Comput. Fluids 27 (1998) 421–433, Re = 1000 (Chebyshev collocation, N = 160),
// centreline tables and primary vortex, in the orientation used here (lid moving in +x, as in
// Ghia et al.): their vortex centre x = 0.4692 is measured in the mirrored orientation, here
// x = 1 − 0.4692 = 0.5308 (public validation data quote the tables in this orientation with the
// vortex at (0.53079, 0.56524), ψ = −0.118936603; the computed centre agrees). u on x = 0.5:
const BP_Y: [f64; 15] = [
    0.0547, 0.0625, 0.0703, 0.1016, 0.1719, 0.2813, 0.4531, 0.5, 0.6172, 0.7344, 0.8516, 0.9531,
    0.9609, 0.9688, 0.9766,
];
const BP_U: [f64; 15] = [
    -0.1812881, -0.2023300, -0.2228955, -0.3004561, -0.3885690, -0.2803696, -0.1081999, -0.0620561,
    0.0570178, 0.1886747, 0.3372212, 0.4723329, 0.5169277, 0.5808359, 0.6644227,
];
// v on y = 0.5:
const BP_X: [f64; 15] = [
    0.0625, 0.0703, 0.0781, 0.0938, 0.1563, 0.2266, 0.2344, 0.5, 0.8047, 0.8594, 0.9063, 0.9453,
    0.9531, 0.9609, 0.9688,
];
const BP_V: [f64; 15] = [
    0.2807056, 0.2962703, 0.3099097, 0.3330442, 0.3769189, 0.3339924, 0.3253592, 0.0257995,
    -0.3202137, -0.4264545, -0.5264392, -0.4103754, -0.3553213, -0.2936869, -0.2279225,
];
/// ψ_min (its location, mirrored to the +x lid, is x = 1 − 0.4692, y = 0.5652).
const BP_PSI_MIN: f64 = -0.1189366;
