//! Torque control in plane strain: the assembly with the hub angle φ as an unknown (see
//! [`super::Transient::enable_torque_control`]). Each cell touching the hub leaves the
//! projections of its hub rows and columns on t_b = e3 × x_b in the [`HubAngle`] store inside
//! the parallel assembly; the φ row and column are then scattered from them.

use super::{DynamicTerms, HubAngle, HUB_STRIDE};
use crate::assembly::{LocalSystem, SharedMut, MAX_LOCAL};
use crate::math::Vec2;
use crate::model::system::SolidSystem;
use crate::model::terms::{CellHook, Inertia, Rates, Terms};
use crate::physics::SolidModel;

/// M acc + s f(x, v) of the plane-strain body (and its tangent), with the hub-angle row and
/// column under torque control.
pub(super) fn assemble_with_hub_angle(
    sys: &mut SolidSystem,
    dt: &DynamicTerms,
    mut hub_angle: Option<&mut HubAngle>,
    is_hub: &[bool],
    with_matrix: bool,
) -> bool {
    let xa = dt.x;
    let ok = {
        // Torque control: each hub cell leaves its projections on t_b = e3 × x_b in `store`.
        let (hub_slot, store) = match hub_angle.as_deref_mut() {
            Some(h) => (Some(&h.hub_slot), Some(SharedMut::new(&mut h.store))),
            None => (None, None),
        };
        let hub_projections = |model: &SolidModel, c: usize, loc: &LocalSystem| {
            let (Some(hs), Some(st)) = (hub_slot, &store) else {
                return;
            };
            let slot = hs[c];
            if slot == u32::MAX {
                return;
            }
            let (nd, nn) = (loc.nd, model.mesh.cell_nodes(c).len());
            let base = slot as usize * HUB_STRIDE;
            // SAFETY: each hub cell writes only its own stride of `store`.
            let w = |i: usize, v: f64| unsafe { st.set(base + i, v) };
            let nodes = model.mesh.cell_nodes(c);
            let pos = |a: usize| {
                let n = nodes[a] as usize;
                model.mesh.nodes[n] + Vec2::new(xa[2 * n], xa[2 * n + 1])
            };
            let hub_t = |a: usize| {
                let x = pos(a);
                Vec2::new(-x[1], x[0])
            };
            let (mut rphi, mut kpp) = (0.0, 0.0);
            for a in (0..nn).filter(|&a| is_hub[nodes[a] as usize]) {
                let (t, x) = (hub_t(a), pos(a));
                rphi += t[0] * loc.r[2 * a] + t[1] * loc.r[2 * a + 1];
                kpp -= x[0] * loc.r[2 * a] + x[1] * loc.r[2 * a + 1];
            }
            w(2 * MAX_LOCAL, rphi);
            if with_matrix {
                // Column K t and row tᵀ K over the local dofs.
                for i in 0..nd {
                    let (mut col, mut row) = (0.0, 0.0);
                    for b in (0..nn).filter(|&b| is_hub[nodes[b] as usize]) {
                        let t = hub_t(b);
                        col += loc.k[i * nd + 2 * b] * t[0] + loc.k[i * nd + 2 * b + 1] * t[1];
                        row += t[0] * loc.k[(2 * b) * nd + i] + t[1] * loc.k[(2 * b + 1) * nd + i];
                    }
                    w(i, col);
                    w(MAX_LOCAL + i, row);
                    if i < 2 * nn && is_hub[nodes[i / 2] as usize] {
                        kpp += hub_t(i / 2)[i % 2] * col;
                    }
                }
                w(2 * MAX_LOCAL + 1, kpp);
            }
        };
        let terms = Terms {
            rates: Rates::Dynamic {
                x: xa,
                v: dt.v,
                kv: dt.kv,
            },
            force_scale: dt.force_scale,
            inertia: Some(Inertia {
                mass: dt.mass,
                offsets: dt.offsets,
                acc: dt.acc,
                ca: dt.ca,
            }),
            cell_hook: hub_slot.map(|_| &hub_projections as CellHook),
        };
        sys.assemble(&terms, with_matrix)
    };
    let Some(h) = hub_angle else {
        return ok;
    };
    // φ row: Σ_b t_b · R_b (scattered from the hub cells) + I φ̈_α − fs T(t).
    if !h.frozen {
        let st = &h.store;
        sys.asm
            .add_block(h.block, &sys.dofs, with_matrix, |e, loc| {
                let base = e * HUB_STRIDE;
                let nd = loc.nd - 1;
                loc.r[nd] = st[base + 2 * MAX_LOCAL];
                if with_matrix {
                    for i in 0..nd {
                        loc.k[i * (nd + 1) + nd] = st[base + i];
                        loc.k[nd * (nd + 1) + i] = st[base + MAX_LOCAL + i];
                    }
                    loc.k[nd * (nd + 1) + nd] = st[base + 2 * MAX_LOCAL + 1];
                }
            });
        let (inertia, torque) = (
            h.inertia * dt.acc[h.iphi],
            dt.force_scale * h.torque.value(dt.t),
        );
        sys.asm.residual[h.eq] += inertia - torque;
        sys.asm.scale[h.eq] += inertia.abs() + torque.abs();
        if with_matrix && h.diag_slot != usize::MAX {
            sys.asm.values[h.diag_slot] += h.inertia * dt.ca;
        }
    } else {
        sys.asm.residual[h.eq] = 0.0;
        if with_matrix && h.diag_slot != usize::MAX {
            sys.asm.values[h.diag_slot] = 1.0;
        }
    }
    ok
}
