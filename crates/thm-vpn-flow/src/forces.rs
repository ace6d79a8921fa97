//! Fluid forces on the spheres (A-Eqs. 52–54).

use crate::channel::two_layer_flow;
use crate::error::FlowError;
use crate::network::Network;
use crate::params::FlowConfig;
use crate::state::FlowState;
use thm_vpn_mesh::NONE;

/// Adds the fluid forces on every sphere \[N\] to `out` (indexed by sphere; `out` is not
/// cleared):
///
/// - pressure (A-Eqs. 52–53): every face between a virtual pore `i` and a solid cell of
///   sphere `j` pushes the sphere with `P_i e_k w n`, `n` the unit normal from the fluid into
///   the solid, `e_k` the face length and `w = 2 r_max` the thickness (the largest sphere
///   diameter, so `A_k = 2 r_max e_k`);
/// - shear (A-Eq. 54): every S2S channel `c` crossing contact `k` between spheres
///   `contact_spheres[k] = [a, b]` drags each of the two spheres along the channel, in the flow
///   direction, with `τ̄ L_c w`, where `τ̄` is the mean of the two wall stresses of the two-layer
///   solution. Which sphere is the liquid-side wall is not defined in the 2D network, so each
///   gets the mean; `τ̄ = G h / 2` for any interface position, and the pair together receives the
///   exact total `G h L w = ΔP h w`.
pub fn add_sphere_forces(
    network: &Network,
    state: &FlowState,
    config: &FlowConfig,
    contact_spheres: &[[u32; 2]],
    out: &mut [[f64; 2]],
) -> Result<(), FlowError> {
    add_pressure_forces(network, state, out)?;
    add_shear_forces(network, state, config, contact_spheres, out)
}

fn sphere_index(
    n_spheres: usize,
    what: &'static str,
    index: usize,
    s: u32,
) -> Result<usize, FlowError> {
    if (s as usize) < n_spheres {
        Ok(s as usize)
    } else {
        Err(FlowError::OutOfRange {
            name: what,
            range: "< number of spheres",
            value: index as f64,
        })
    }
}

/// The pressure part of [`add_sphere_forces`] alone (A-Eqs. 52–53): `P_i e_k w n` on the
/// sphere behind every wall face.
pub fn add_pressure_forces(
    network: &Network,
    state: &FlowState,
    out: &mut [[f64; 2]],
) -> Result<(), FlowError> {
    let parts = network.parts();
    let w = network.width();
    let ns = out.len();
    let sphere_index = |what, index, s| sphere_index(ns, what, index, s);
    for k in 0..parts.wall_pore.len() {
        let s = sphere_index("wall face sphere", k, parts.wall_sphere[k])?;
        let p = state.pressure[parts.wall_pore[k] as usize];
        let a = parts.wall_length[k] * w;
        let n = parts.wall_normal[k];
        out[s][0] += p * n[0] * a;
        out[s][1] += p * n[1] * a;
    }
    Ok(())
}

/// The shear part of [`add_sphere_forces`] alone (A-Eq. 54): the mean wall stress of every
/// S2S channel on the two spheres of its contact.
pub fn add_shear_forces(
    network: &Network,
    state: &FlowState,
    config: &FlowConfig,
    contact_spheres: &[[u32; 2]],
    out: &mut [[f64; 2]],
) -> Result<(), FlowError> {
    let parts = network.parts();
    let w = network.width();
    let ns = out.len();
    let sphere_index = |what, index, s| sphere_index(ns, what, index, s);
    for c in 0..network.n_channels() {
        let contact = parts.channel_contact[c];
        if contact == NONE {
            continue;
        }
        let Some(&[sa, sb]) = contact_spheres.get(contact as usize) else {
            return Err(FlowError::OutOfRange {
                name: "S2S channel contact",
                range: "< number of contacts",
                value: contact as f64,
            });
        };
        let [i, j] = parts.channel_pores[c];
        let (i, j) = (i as usize, j as usize);
        let len = parts.channel_length[c];
        let g = (state.pressure[i] - state.pressure[j]) / len;
        let up = if g >= 0.0 { i } else { j };
        let flow = two_layer_flow(
            parts.channel_aperture[c],
            state.liquid_fraction[up],
            g,
            config.liquid_viscosity(),
            config.gas_viscosity(),
        );
        // Positive τ̄ drags along the direction first pore → second pore.
        let f = flow.mean_wall_shear() * len * w;
        let d = parts.channel_direction[c];
        for s in [sa, sb] {
            let s = sphere_index("contact sphere", contact as usize, s)?;
            out[s][0] += f * d[0];
            out[s][1] += f * d[1];
        }
    }
    Ok(())
}
