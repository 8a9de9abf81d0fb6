//! The equations of motion (MODELS.md §5): the right-hand side the integrator calls, the static
//! equilibrium the integration starts from, and the mechanical energy the tests check.
//!
//! State (12 values, scaled so that one error tolerance fits every component):
//! `[x_s, y_s, x_p, y_p, u_x, u_y]` in µm and their velocities divided by `Ω_ref = 10⁴ rad/s`
//! (also µm), with `u = (resonator − housing)` the resonator's displacement *relative* to the
//! housing. Why relative: the sensor signal is `ÿ_r = −(k_r·u_y + c_r·u̇_y)/m_r`, and `u_y` is
//! some 10⁵ times smaller than the housing's static deflection; as a difference of two absolute
//! positions it would drown in their rounding and integration error.
//!
//! Contact of ball `j` at `φ_j = φ₀ + 2πj/Z + ω_c·t + ψ(t)` (`ψ` the slip walk):
//! `δ_j = (x_s − x_p)·cos φ_j + (y_s − y_p)·sin φ_j − c − H_j(t)`,
//! `f_j = k_b·δ_j^{3/2}` for `δ_j > 0`. The load `F_r` pulls the shaft to −y, so the load zone
//! is around `φ = −π/2`. `H_j` is the defect's extra clearance, a half sine over its width:
//! fixed on the outer race, turning with the shaft on the inner race, and on the ball, at the
//! outer contact when the ball's spin angle is near 0 and at the inner contact near π.

use super::params::{Dof, PhysicsParams};
use crate::random::Rng;
use crate::twin::SimulatedFault;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Length unit of the state: 1 µm.
pub(crate) const LENGTH_SCALE: f64 = 1e6;
/// Velocity states are velocities divided by this, rad/s.
pub(crate) const OMEGA_REF: f64 = 1e4;
pub(crate) const STATE_LEN: usize = 12;
pub(crate) type State = ode_solvers::SVector<f64, STATE_LEN>;

/// Angle wrapped into `[−π, π)`.
fn wrap(angle: f64) -> f64 {
    angle - TAU * (angle / TAU + 0.5).floor()
}

/// Where the defect is and how deep the ball drops into it.
#[derive(Debug, Clone, Copy)]
enum Defect {
    None,
    /// Fixed at `centre` (rad) on the outer race.
    Outer {
        centre: f64,
        half_width: f64,
        drop_m: f64,
    },
    /// At `centre + ω_s·t` on the inner race.
    Inner {
        centre: f64,
        half_width: f64,
        drop_m: f64,
    },
    /// On ball 0, at spin angle `spin0 + ω_spin·t` (0: facing the outer race).
    Ball {
        spin0: f64,
        half_width: f64,
        drop_outer_m: f64,
        drop_inner_m: f64,
    },
}

/// The cage's slip: a random walk of its angle, one step per ball pass, linear in between.
#[derive(Debug, Clone)]
pub(crate) struct SlipWalk {
    node_interval_s: f64,
    step_std_rad: f64,
    /// Node index of `values[0]`.
    first_node: u64,
    values: Vec<f64>,
    rng: Rng,
}

impl SlipWalk {
    fn new(node_interval_s: f64, step_std_rad: f64, seed: u64) -> Self {
        SlipWalk {
            node_interval_s,
            step_std_rad,
            first_node: 0,
            values: vec![0.0],
            rng: Rng::new(seed ^ 0x51_1B_CA_6E),
        }
    }

    /// Makes the walk known on `[from_s, until_s]`, forgetting nodes before `from_s`.
    pub(crate) fn extend(&mut self, from_s: f64, until_s: f64) {
        if self.step_std_rad == 0.0 {
            return;
        }
        let keep_from = ((from_s / self.node_interval_s).floor() as u64).saturating_sub(1);
        if keep_from > self.first_node {
            let drop = ((keep_from - self.first_node) as usize).min(self.values.len() - 1);
            self.values.drain(..drop);
            self.first_node += drop as u64;
        }
        let last_needed = (until_s / self.node_interval_s).ceil() as u64 + 1;
        while self.first_node + (self.values.len() as u64) <= last_needed {
            let last = self.values[self.values.len() - 1];
            self.values
                .push(last + self.step_std_rad * self.rng.normal());
        }
    }

    /// `ψ(t)`; outside the known nodes the nearest known value.
    fn at(&self, t: f64) -> f64 {
        if self.step_std_rad == 0.0 {
            return 0.0;
        }
        let position = t / self.node_interval_s - self.first_node as f64;
        let index = position.floor();
        if index < 0.0 {
            return self.values[0];
        }
        let i = index as usize;
        if i + 1 >= self.values.len() {
            return self.values[self.values.len() - 1];
        }
        let fraction = position - index;
        self.values[i] + fraction * (self.values[i + 1] - self.values[i])
    }
}

/// The model with every constant precomputed, in SI units.
#[derive(Debug, Clone)]
pub(crate) struct Dynamics {
    ms: f64,
    ks: f64,
    cs: f64,
    mp: f64,
    kp: f64,
    cp: f64,
    mr: f64,
    kr: f64,
    cr: f64,
    kb: f64,
    clearance: f64,
    load: f64,
    five_dof: bool,
    balls: usize,
    /// `cos`, `sin` of the angle between neighbouring balls.
    pitch_rotation: (f64, f64),
    phi0: f64,
    omega_shaft: f64,
    omega_cage: f64,
    omega_spin: f64,
    defect: Defect,
    pub(crate) slip: SlipWalk,
}

/// How far a ball drops into a gap of width `width` between two surfaces of curvature radii
/// `r_ball` and `r_race` (race concave: `r_race` negative): the ball's sagitta minus the race's.
fn drop_into_gap(width: f64, r_ball: f64, r_race: f64) -> f64 {
    let sagitta = |r: f64| {
        let r = r.abs();
        let half = (width / 2.0).min(r);
        r - (r * r - half * half).sqrt()
    };
    let race = sagitta(r_race) * r_race.signum();
    (sagitta(r_ball) + race).max(0.0)
}

impl Dynamics {
    pub(crate) fn new(params: &PhysicsParams) -> Self {
        let s = &params.structure;
        let g = &params.bearing;
        let freqs = g.fault_frequencies(params.rpm / 60.0);
        let z = g.rolling_elements as usize;
        let d = g.element_diameter_mm * 1e-3;
        let cos_alpha = g.contact_angle_deg.to_radians().cos();
        let pitch = g.pitch_diameter_mm * 1e-3;
        let r_ball = d / 2.0;
        let r_outer = (pitch + d * cos_alpha) / 2.0;
        let r_inner = (pitch - d * cos_alpha) / 2.0;
        let width = params.defect_width_mm * 1e-3;
        let depth = params.defect_depth_mm * 1e-3;
        let angle = params.defect_angle_deg.to_radians();
        let load_line = -FRAC_PI_2;
        let defect = match params.fault {
            // `PhysicsParams::validate` refuses a cage fault before a model is built.
            SimulatedFault::None | SimulatedFault::Cage => Defect::None,
            SimulatedFault::OuterRace => Defect::Outer {
                centre: load_line + angle,
                half_width: width / (2.0 * r_outer),
                // The outer race is concave towards the ball.
                drop_m: drop_into_gap(width, r_ball, -r_outer).min(depth),
            },
            SimulatedFault::InnerRace => Defect::Inner {
                centre: load_line + angle,
                half_width: width / (2.0 * r_inner),
                drop_m: drop_into_gap(width, r_ball, r_inner).min(depth),
            },
            SimulatedFault::Ball => Defect::Ball {
                spin0: angle,
                half_width: width / (2.0 * r_ball),
                drop_outer_m: drop_into_gap(width, r_ball, -r_outer).min(depth),
                drop_inner_m: drop_into_gap(width, r_ball, r_inner).min(depth),
            },
        };
        let pitch_angle = TAU / z as f64;
        let ball_pass_s = 1.0 / freqs.bpfo.max(1e-9);
        Dynamics {
            ms: s.shaft_mass_kg,
            ks: s.shaft_stiffness,
            cs: s.shaft_damping,
            mp: s.housing_mass_kg,
            kp: s.housing_stiffness,
            cp: s.housing_damping,
            mr: s.resonator_mass_kg,
            kr: s.resonator_stiffness,
            cr: s.resonator_damping,
            kb: s.contact_stiffness,
            clearance: s.clearance_m,
            load: params.load_n,
            five_dof: params.dof == Dof::Five,
            balls: z,
            pitch_rotation: (pitch_angle.cos(), pitch_angle.sin()),
            phi0: load_line,
            omega_shaft: TAU * freqs.shaft,
            omega_cage: TAU * freqs.ftf,
            omega_spin: TAU * freqs.bsf,
            defect,
            slip: SlipWalk::new(ball_pass_s, params.slip * pitch_angle, params.seed),
        }
    }

    /// How long a ball takes to cross the defect, s (infinite without a defect): the
    /// integrator's largest step must stay well below it, or a step could jump over the defect.
    pub(crate) fn defect_transit_s(&self) -> f64 {
        match self.defect {
            Defect::None => f64::INFINITY,
            Defect::Outer { half_width, .. } => 2.0 * half_width / self.omega_cage,
            Defect::Inner { half_width, .. } => {
                2.0 * half_width / (self.omega_shaft - self.omega_cage).abs()
            }
            Defect::Ball { half_width, .. } => 2.0 * half_width / self.omega_spin,
        }
    }

    /// The highest natural frequency of the linear part, rad/s (an upper estimate: the
    /// resonator against the housing, the shaft on its support plus a stiff contact).
    pub(crate) fn highest_mode_rad_s(&self) -> f64 {
        let resonator = (self.kr * (1.0 / self.mr + 1.0 / self.mp)).sqrt();
        // Contact stiffness linearised at a generous 50 µm deflection, all balls.
        let contact = 1.5 * self.kb * (50e-6f64).sqrt() * self.balls as f64 / 2.0;
        let shaft = ((self.ks + contact) / self.ms).sqrt();
        resonator.max(shaft)
    }

    /// The extra clearance the defect opens at ball `j` (angle `phi`) at time `t`, m.
    fn defect_gap(&self, j: usize, phi: f64, t: f64) -> f64 {
        let half_sine = |offset: f64, half_width: f64, drop: f64| {
            if offset.abs() < half_width {
                drop * (FRAC_PI_2 * offset / half_width).cos()
            } else {
                0.0
            }
        };
        match self.defect {
            Defect::None => 0.0,
            Defect::Outer {
                centre,
                half_width,
                drop_m,
            } => half_sine(wrap(phi - centre), half_width, drop_m),
            Defect::Inner {
                centre,
                half_width,
                drop_m,
            } => half_sine(
                wrap(phi - centre - self.omega_shaft * t),
                half_width,
                drop_m,
            ),
            Defect::Ball {
                spin0,
                half_width,
                drop_outer_m,
                drop_inner_m,
            } if j == 0 => {
                let spin = spin0 + self.omega_spin * t;
                half_sine(wrap(spin), half_width, drop_outer_m)
                    + half_sine(wrap(spin - PI), half_width, drop_inner_m)
            }
            Defect::Ball { .. } => 0.0,
        }
    }

    /// Calls `each(δ_j, cos φ_j, sin φ_j)` for every ball at time `t` and relative shaft
    /// displacement `(ex, ey)` (m).
    #[inline]
    fn for_each_ball(&self, t: f64, ex: f64, ey: f64, mut each: impl FnMut(f64, f64, f64)) {
        let cage = self.phi0 + self.omega_cage * t + self.slip.at(t);
        let (mut sin, mut cos) = cage.sin_cos();
        let (rc, rs) = self.pitch_rotation;
        for j in 0..self.balls {
            let mut delta = ex * cos + ey * sin - self.clearance;
            if !matches!(self.defect, Defect::None) {
                let phi = cage + TAU * j as f64 / self.balls as f64;
                delta -= self.defect_gap(j, phi, t);
            }
            each(delta, cos, sin);
            (cos, sin) = (cos * rc - sin * rs, sin * rc + cos * rs);
        }
    }

    /// The contact force on the housing (the shaft gets its opposite), N.
    #[inline]
    fn contact_force(&self, t: f64, ex: f64, ey: f64) -> (f64, f64) {
        let (mut fx, mut fy) = (0.0, 0.0);
        let kb = self.kb;
        self.for_each_ball(t, ex, ey, |delta, cos, sin| {
            if delta > 0.0 {
                let f = kb * delta * delta.sqrt();
                fx += f * cos;
                fy += f * sin;
            }
        });
        (fx, fy)
    }

    /// `dy/dt` of the scaled state.
    pub(crate) fn rhs(&self, t: f64, y: &State, dy: &mut State) {
        let to_m = 1.0 / LENGTH_SCALE;
        let to_mps = OMEGA_REF / LENGTH_SCALE;
        let (xs, ys, xp, yp, ux, uy) = (
            y[0] * to_m,
            y[1] * to_m,
            y[2] * to_m,
            y[3] * to_m,
            y[4] * to_m,
            y[5] * to_m,
        );
        let (vxs, vys, vxp, vyp, vux, vuy) = (
            y[6] * to_mps,
            y[7] * to_mps,
            y[8] * to_mps,
            y[9] * to_mps,
            y[10] * to_mps,
            y[11] * to_mps,
        );
        let (fx, fy) = self.contact_force(t, xs - xp, ys - yp);
        let axs = (-self.cs * vxs - self.ks * xs - fx) / self.ms;
        let ays = (-self.cs * vys - self.ks * ys - fy - self.load) / self.ms;
        let (resonator_x, arx) = if self.five_dof {
            (0.0, 0.0)
        } else {
            let force = self.kr * ux + self.cr * vux;
            (force, -force / self.mr)
        };
        let resonator_y = self.kr * uy + self.cr * vuy;
        let ary = -resonator_y / self.mr;
        let axp = (-self.cp * vxp - self.kp * xp + fx + resonator_x) / self.mp;
        let ayp = (-self.cp * vyp - self.kp * yp + fy + resonator_y) / self.mp;
        let aux = if self.five_dof { 0.0 } else { arx - axp };
        let auy = ary - ayp;
        for (position_rate, velocity) in dy.iter_mut().zip(y.iter().skip(6)).take(6) {
            *position_rate = OMEGA_REF * velocity;
        }
        let to_state = LENGTH_SCALE / OMEGA_REF;
        for (i, a) in [axs, ays, axp, ayp, aux, auy].into_iter().enumerate() {
            dy[6 + i] = a * to_state;
        }
        if self.five_dof {
            dy[4] = 0.0;
        }
    }

    /// The sensor signal: the resonator's vertical acceleration `ÿ_r`, m/s².
    pub(crate) fn sensor_acceleration(&self, y: &State) -> f64 {
        let uy = y[5] / LENGTH_SCALE;
        let vuy = y[11] * OMEGA_REF / LENGTH_SCALE;
        -(self.kr * uy + self.cr * vuy) / self.mr
    }

    /// The static equilibrium under the load at t = 0 (velocities and the resonators' relative
    /// displacements zero): Newton on the shaft-to-housing displacement `e`, with
    /// `s = (F − f(e))/k_s`, `p = f(e)/k_p` and `e = s − p`.
    pub(crate) fn equilibrium(&self) -> State {
        let compliance = 1.0 / self.ks + 1.0 / self.kp;
        let (mut ex, mut ey) = (0.0, -self.load / self.ks);
        for _ in 0..200 {
            let (fx, fy) = self.contact_force(0.0, ex, ey);
            let (mut jxx, mut jxy, mut jyy) = (0.0, 0.0, 0.0);
            self.for_each_ball(0.0, ex, ey, |delta, cos, sin| {
                if delta > 0.0 {
                    let k = 1.5 * self.kb * delta.sqrt();
                    jxx += k * cos * cos;
                    jxy += k * cos * sin;
                    jyy += k * sin * sin;
                }
            });
            let gx = ex + compliance * fx;
            let gy = ey + compliance * fy + self.load / self.ks;
            let (axx, axy, ayy) = (
                1.0 + compliance * jxx,
                compliance * jxy,
                1.0 + compliance * jyy,
            );
            let det = axx * ayy - axy * axy;
            let dx = (ayy * gx - axy * gy) / det;
            let dy = (axx * gy - axy * gx) / det;
            ex -= dx;
            ey -= dy;
            if dx.abs().max(dy.abs()) < 1e-16 {
                break;
            }
        }
        let (fx, fy) = self.contact_force(0.0, ex, ey);
        let (xs, ys) = (-fx / self.ks, (-self.load - fy) / self.ks);
        let (xp, yp) = (fx / self.kp, fy / self.kp);
        let mut state = State::zeros();
        for (i, v) in [xs, ys, xp, yp].into_iter().enumerate() {
            state[i] = v * LENGTH_SCALE;
        }
        state
    }

    /// Total mechanical energy (kinetic, springs, Hertz contacts `2/5·k_b·δ^{5/2}`, and the
    /// load's potential `F_r·y_s`), J. Conserved without damping and rotation.
    #[cfg(test)]
    pub(crate) fn energy(&self, t: f64, y: &State) -> f64 {
        let m = |i: usize| y[i] / LENGTH_SCALE;
        let v = |i: usize| y[6 + i] * OMEGA_REF / LENGTH_SCALE;
        let kinetic = 0.5 * self.ms * (v(0).powi(2) + v(1).powi(2))
            + 0.5 * self.mp * (v(2).powi(2) + v(3).powi(2))
            + 0.5 * self.mr * ((v(2) + v(4)).powi(2) + (v(3) + v(5)).powi(2));
        let springs = 0.5 * self.ks * (m(0).powi(2) + m(1).powi(2))
            + 0.5 * self.kp * (m(2).powi(2) + m(3).powi(2))
            + 0.5 * self.kr * (m(4).powi(2) + m(5).powi(2));
        let mut contact = 0.0;
        self.for_each_ball(t, m(0) - m(2), m(1) - m(3), |delta, _, _| {
            if delta > 0.0 {
                contact += 0.4 * self.kb * delta.powf(2.5);
            }
        });
        kinetic + springs + contact + self.load * m(1)
    }

    #[cfg(test)]
    pub(crate) fn without_damping_or_rotation(mut self) -> Self {
        self.cs = 0.0;
        self.cp = 0.0;
        self.cr = 0.0;
        self.omega_shaft = 0.0;
        self.omega_cage = 0.0;
        self.omega_spin = 0.0;
        self
    }

    /// This model's damping with `other`'s speeds.
    #[cfg(test)]
    pub(crate) fn with_rotation_of(mut self, other: &Dynamics) -> Self {
        self.omega_shaft = other.omega_shaft;
        self.omega_cage = other.omega_cage;
        self.omega_spin = other.omega_spin;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equilibrium_balances_the_load() {
        let p = PhysicsParams::cwru(SimulatedFault::None).unwrap();
        let dynamics = Dynamics::new(&p);
        let y = dynamics.equilibrium();
        let mut dy = State::zeros();
        dynamics.rhs(0.0, &y, &mut dy);
        // Accelerations of the equilibrium are zero to rounding (in m/s²).
        let worst = (6..12)
            .map(|i| (dy[i] * OMEGA_REF / LENGTH_SCALE).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "residual acceleration {worst} m/s²");
        // The shaft sits below the housing: the load zone is at the bottom.
        assert!(y[1] < y[3], "{y:?}");
    }

    #[test]
    fn drop_into_a_defect_follows_the_curvatures() {
        // 0.178 mm over a 3.97 mm ball on the 6205's outer race (23.49 mm): about 0.83 µm.
        let outer = drop_into_gap(0.1778e-3, 3.97e-3, -23.49e-3);
        let inner = drop_into_gap(0.1778e-3, 3.97e-3, 15.55e-3);
        assert!((outer - 0.83e-6).abs() < 0.02e-6, "{outer}");
        assert!(inner > outer);
    }

    #[test]
    fn wrap_stays_in_minus_pi_to_pi() {
        for a in [-7.0, -PI, 0.0, 3.0, PI, 10.0] {
            let w = wrap(a);
            assert!((-PI..PI).contains(&w), "{a} -> {w}");
            assert!(((a - w) / TAU - ((a - w) / TAU).round()).abs() < 1e-12);
        }
    }
}
