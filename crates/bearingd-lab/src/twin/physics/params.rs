//! What defines a physics-twin record: the bearing and its operating point, the defect, the
//! lumped masses, stiffnesses and dampings of the 6-DOF model, the sensor's sample rate, noise
//! and seed; their defaults with their sources; and the validation that turns any unusable value
//! into an error that names the parameter and the fix (never a panic, never a NaN record).

use crate::bearing::BearingGeometry;
use crate::twin::SimulatedFault;
use serde::{Deserialize, Serialize};

/// Which lumped model to integrate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dof {
    /// Seed 001: shaft (x, y), housing (x, y) and a resonator on the housing in x and y.
    Six,
    /// Seed 003: the same without the horizontal resonator (shaft x, y; housing x, y;
    /// resonator y).
    Five,
}

/// The lumped structure: masses (kg), stiffnesses (N/m), dampings (N·s/m), the Hertz contact
/// stiffness of one ball (N/m^1.5) and the radial clearance (m).
///
/// Defaults (`Structure::for_bearing`): seed 001's own parameter table did not survive the text
/// extraction, so the values are the ones this family of models (Sawalhi & Randall 2008,
/// "Simulating gear and bearing interactions in the presence of faults", MSSP 22, and the
/// papers that reuse it, among them seed 003's reference 20) is run with: shaft and inner ring
/// `m_s` 1.2638 kg, `k_s` 7.42·10⁷ N/m, `c_s` 1376.8 N·s/m; housing and outer ring `m_p` 6 kg,
/// `k_p` 1.51·10⁷ N/m, `c_p` 2210.7 N·s/m; resonator `m_r` 1 kg, `k_r` 8.8826·10⁹ N/m,
/// `c_r` 9424.8 N·s/m (a 15 kHz resonance with 5 % damping). The contact stiffness `k_b` is
/// computed from the bearing's geometry by Hertz theory ([`hertz_contact_stiffness`]); for the
/// SKF 6205 it gives 8.76·10⁹ N/m^1.5, the value the literature uses for that bearing.
/// These are starting values, not measurements of any machine: `bearingd calibrate` fits
/// `k_r`, `c_r` and `k_b` to a measured record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Structure {
    pub shaft_mass_kg: f64,
    pub shaft_stiffness: f64,
    pub shaft_damping: f64,
    pub housing_mass_kg: f64,
    pub housing_stiffness: f64,
    pub housing_damping: f64,
    pub resonator_mass_kg: f64,
    /// `k_r`, N/m: with `m_r` it sets the resonance the defect excites.
    pub resonator_stiffness: f64,
    /// `c_r`, N·s/m: the resonance's damping (its bandwidth).
    pub resonator_damping: f64,
    /// `k_b`, N/m^1.5: one ball's Hertz load–deflection constant, `f = k_b·δ^{3/2}`.
    pub contact_stiffness: f64,
    /// Radial clearance `c`, m.
    pub clearance_m: f64,
}

impl Structure {
    /// The default structure for `bearing` (see the type's documentation for the sources).
    pub fn for_bearing(bearing: &BearingGeometry) -> Self {
        Structure {
            shaft_mass_kg: 1.2638,
            shaft_stiffness: 7.42e7,
            shaft_damping: 1376.8,
            housing_mass_kg: 6.0,
            housing_stiffness: 1.51e7,
            housing_damping: 2210.7,
            resonator_mass_kg: 1.0,
            resonator_stiffness: 8.8826e9,
            resonator_damping: 9424.8,
            contact_stiffness: hertz_contact_stiffness(bearing),
            // (choice) 2 µm: a small positive clearance, below the CN class of a 25 mm bore
            // deep-groove bearing (6–20 µm radial play is common; the load takes up part).
            clearance_m: 2e-6,
        }
    }

    /// The resonator's undamped natural frequency `√(k_r/m_r)/2π`, Hz.
    pub fn resonance_hz(&self) -> f64 {
        (self.resonator_stiffness / self.resonator_mass_kg).sqrt() / std::f64::consts::TAU
    }

    /// The resonator's damping ratio `c_r / (2·√(k_r·m_r))`.
    pub fn resonator_damping_ratio(&self) -> f64 {
        self.resonator_damping / (2.0 * (self.resonator_stiffness * self.resonator_mass_kg).sqrt())
    }
}

/// Young's modulus and Poisson's ratio of bearing steel (AISI 52100).
const STEEL_E_PA: f64 = 208e9;
const STEEL_POISSON: f64 = 0.3;
/// Groove radius over ball diameter, inner and outer race: typical of deep-groove ball bearings
/// (Harris & Kotzalas, Rolling Bearing Analysis, 5th ed., §2).
const INNER_GROOVE_CONFORMITY: f64 = 0.52;
const OUTER_GROOVE_CONFORMITY: f64 = 0.53;

/// One ball's Hertz load–deflection constant `K` (N/m^1.5), inner and outer contact in series:
/// `K = (K_i^{-2/3} + K_o^{-2/3})^{-3/2}`, each contact
/// `K_j = π·k·E′·√(2·ℰ·R / (9·ℱ³))` with the Hamrock–Brewe approximations of the ellipticity
/// `k = 1.0339·(R_y/R_x)^0.636` and of the elliptic integrals `ℰ = 1.0003 + 0.5968·R_x/R_y`,
/// `ℱ = 1.5277 + 0.6023·ln(R_y/R_x)`; `R_x`, `R_y` the effective radii in the rolling and
/// transverse directions, `E′ = E/(1 − ν²)`.
pub fn hertz_contact_stiffness(bearing: &BearingGeometry) -> f64 {
    let d = bearing.element_diameter_mm * 1e-3;
    let pitch = bearing.pitch_diameter_mm * 1e-3;
    let cos_alpha = bearing.contact_angle_deg.to_radians().cos();
    let e_prime = STEEL_E_PA / (1.0 - STEEL_POISSON * STEEL_POISSON);
    let contact = |inverse_rx: f64, inverse_ry: f64| {
        let ratio = inverse_rx / inverse_ry; // R_y / R_x
        let ellipticity = 1.0339 * ratio.powf(0.636);
        let second_kind = 1.0003 + 0.5968 / ratio;
        let first_kind = 1.5277 + 0.6023 * ratio.ln();
        let radius = 1.0 / (inverse_rx + inverse_ry);
        std::f64::consts::PI
            * ellipticity
            * e_prime
            * (2.0 * second_kind * radius / (9.0 * first_kind.powi(3))).sqrt()
    };
    let inner_race_radius = (pitch - d * cos_alpha) / 2.0;
    let outer_race_radius = (pitch + d * cos_alpha) / 2.0;
    let inner = contact(
        2.0 / d + 1.0 / inner_race_radius,
        2.0 / d - 1.0 / (INNER_GROOVE_CONFORMITY * d),
    );
    let outer = contact(
        2.0 / d - 1.0 / outer_race_radius,
        2.0 / d - 1.0 / (OUTER_GROOVE_CONFORMITY * d),
    );
    (inner.powf(-2.0 / 3.0) + outer.powf(-2.0 / 3.0)).powf(-1.5)
}

/// Everything that defines a physics-twin record. Build it with [`PhysicsParams::new`] (the
/// defaults) and change the fields you need; [`PhysicsParams::validate`] says what is wrong.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhysicsParams {
    pub bearing: BearingGeometry,
    /// Shaft speed, rpm (the inner ring turns, the outer ring stands).
    pub rpm: f64,
    /// Radial load on the shaft, N, downwards (−y). Default 1000 N (choice).
    pub load_n: f64,
    pub fault: SimulatedFault,
    /// Circumferential width `L` of the defect, mm (CWRU's seeded faults: 0.178, 0.356,
    /// 0.533 mm). Ignored without a fault.
    pub defect_width_mm: f64,
    /// Depth of the defect, mm: the ball drops by the smaller of this and what the geometry
    /// allows (the sagitta of the ball and the race over the width). Default 0.28 mm (CWRU's
    /// electro-discharge pits are 0.011 in deep).
    pub defect_depth_mm: f64,
    /// Angle of the defect from the load line at t = 0, degrees (0: the middle of the load zone).
    /// For an inner-race defect it then turns with the shaft; for a ball defect it is the spin
    /// angle of the defect (0: facing the outer race).
    pub defect_angle_deg: f64,
    pub structure: Structure,
    pub dof: Dof,
    /// Sample rate of the simulated sensor, Hz.
    pub fs_hz: f64,
    /// Length of the record [`super::simulate`] returns, s.
    pub duration_s: f64,
    /// Cage slip: standard deviation of each ball-pass interval as a fraction of it (a random
    /// walk of the cage angle; real bearings slip 1–2 %). 0: the kinematic cage speed exactly.
    pub slip: f64,
    /// Standard deviation of white noise added to the sensor signal, g.
    pub noise_g: f64,
    /// Seed of the noise and slip: the same parameters and seed give the same record.
    pub seed: u64,
    /// Relative tolerance of the adaptive integrator (docs/PHYSICS.md: accuracy vs
    /// tolerance). Default 1e-6.
    pub tolerance: f64,
}

impl PhysicsParams {
    /// The defaults for `bearing` at `rpm` with `fault`: a 0.178 mm (0.007 in) defect in the
    /// middle of the load zone, 1000 N, the 6-DOF model, 12 kHz, 1 s, no slip, no noise.
    pub fn new(bearing: BearingGeometry, rpm: f64, fault: SimulatedFault) -> Self {
        PhysicsParams {
            structure: Structure::for_bearing(&bearing),
            bearing,
            rpm,
            load_n: 1000.0,
            fault,
            defect_width_mm: 0.1778,
            defect_depth_mm: 0.2794,
            defect_angle_deg: 0.0,
            dof: Dof::Six,
            fs_hz: 12_000.0,
            duration_s: 1.0,
            slip: 0.0,
            noise_g: 0.0,
            seed: 1,
            tolerance: 1e-6,
        }
    }

    /// The CWRU drive-end case: SKF 6205-2RS at 1797 rpm, 12 kHz (the tests' and the bench's
    /// case); an error only if the catalog lost the 6205.
    pub fn cwru(fault: SimulatedFault) -> Result<Self, crate::bearing::BearingError> {
        let bearing = BearingGeometry::from_catalog("skf-6205-2rs")?;
        Ok(PhysicsParams::new(bearing, 1797.0, fault))
    }

    /// Checks every parameter; the error lists every problem with its fix.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        let mut problems = Vec::new();
        let mut check = |ok: bool, problem: String| {
            if !ok {
                problems.push(problem);
            }
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        check(
            self.fault != crate::twin::SimulatedFault::Cage,
            "the physics twin has no damaged-cage model (a cage pocket is not a race or ball \
             defect it can integrate); simulate a cage fault with the signal model (--model signal)"
                .to_string(),
        );
        let g = &self.bearing;
        check(
            g.rolling_elements >= 3
                && positive(g.element_diameter_mm)
                && positive(g.pitch_diameter_mm)
                && g.element_diameter_mm < g.pitch_diameter_mm
                && (0.0..90.0).contains(&g.contact_angle_deg),
            format!(
                "bearing {g} is not a usable geometry; give z ≥ 3 and 0 < d < D, alpha in [0, 90)"
            ),
        );
        check(
            positive(self.rpm) && self.rpm <= 100_000.0,
            format!(
                "rpm {} must be a shaft speed in (0, 100000], e.g. 1797",
                self.rpm
            ),
        );
        check(
            self.load_n.is_finite() && (0.0..=1e6).contains(&self.load_n),
            format!("load {} N must be in [0, 1e6] N, e.g. 1000", self.load_n),
        );
        check(
            self.fs_hz.is_finite() && (1_000.0..=1e6).contains(&self.fs_hz),
            format!(
                "sample rate {} Hz must be in [1000, 1e6] Hz, e.g. 12000",
                self.fs_hz
            ),
        );
        check(
            positive(self.duration_s) && self.duration_s * self.fs_hz <= 1e9,
            format!(
                "duration {} s must be positive and give at most 10⁹ samples at {} Hz",
                self.duration_s, self.fs_hz
            ),
        );
        check(
            self.noise_g.is_finite() && self.noise_g >= 0.0,
            format!("noise {} g must be ≥ 0", self.noise_g),
        );
        check(
            self.slip.is_finite() && (0.0..0.2).contains(&self.slip),
            format!("slip {} must be in [0, 0.2), e.g. 0.01 for 1 %", self.slip),
        );
        check(
            self.tolerance.is_finite() && (1e-12..=1e-2).contains(&self.tolerance),
            format!(
                "integrator tolerance {} must be in [1e-12, 1e-2], e.g. 1e-6",
                self.tolerance
            ),
        );
        check(
            self.defect_angle_deg.is_finite(),
            format!(
                "defect angle {} must be a finite angle in degrees",
                self.defect_angle_deg
            ),
        );
        if self.fault != SimulatedFault::None {
            check(
                positive(self.defect_width_mm) && self.defect_width_mm < g.element_diameter_mm,
                format!(
                    "defect width {} mm must be positive and below the ball diameter {} mm, e.g. 0.178",
                    self.defect_width_mm, g.element_diameter_mm
                ),
            );
            check(
                positive(self.defect_depth_mm),
                format!(
                    "defect depth {} mm must be positive, e.g. 0.28",
                    self.defect_depth_mm
                ),
            );
        }
        let s = &self.structure;
        for (name, value) in [
            ("shaft mass m_s (kg)", s.shaft_mass_kg),
            ("housing mass m_p (kg)", s.housing_mass_kg),
            ("resonator mass m_r (kg)", s.resonator_mass_kg),
            ("shaft stiffness k_s (N/m)", s.shaft_stiffness),
            ("housing stiffness k_p (N/m)", s.housing_stiffness),
            ("resonator stiffness k_r (N/m)", s.resonator_stiffness),
            ("contact stiffness k_b (N/m^1.5)", s.contact_stiffness),
        ] {
            check(
                positive(value) && value < 1e15,
                format!("{name} = {value} must be positive and below 1e15"),
            );
        }
        for (name, value) in [
            ("shaft damping c_s (N·s/m)", s.shaft_damping),
            ("housing damping c_p (N·s/m)", s.housing_damping),
            ("resonator damping c_r (N·s/m)", s.resonator_damping),
        ] {
            check(
                value.is_finite() && (0.0..1e9).contains(&value),
                format!("{name} = {value} must be in [0, 1e9)"),
            );
        }
        check(
            s.clearance_m.is_finite() && (-1e-4..=1e-3).contains(&s.clearance_m),
            format!(
                "clearance {} m must be in [-1e-4, 1e-3] m (negative: preload), e.g. 2e-6",
                s.clearance_m
            ),
        );
        if problems.is_empty() {
            Ok(())
        } else {
            Err(PhysicsError::Invalid {
                problems: problems.join("; "),
            })
        }
    }

    /// The number of samples [`super::simulate`] returns.
    pub fn samples(&self) -> usize {
        (self.duration_s * self.fs_hz).round().max(0.0) as usize
    }
}

/// Why a physics record could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PhysicsError {
    #[error("physics model parameters not usable: {problems}")]
    Invalid { problems: String },
    #[error("the physics model's integration failed at t = {time_s:.6} s: {reason}; the parameters make the model too stiff or unstable (lower k_r or k_b, or raise the damping), or loosen the tolerance")]
    Integration { time_s: f64, reason: String },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hertz_stiffness_of_the_6205_matches_the_literature_value() {
        let bearing = BearingGeometry::from_catalog("skf-6205-2rs").unwrap();
        let k = hertz_contact_stiffness(&bearing);
        // 8.753e9 N/m^1.5 is the value used for the CWRU drive-end bearing in the literature.
        assert!((k / 8.753e9 - 1.0).abs() < 0.01, "{k:e}");
    }

    #[test]
    fn defaults_are_valid_and_every_problem_is_listed() {
        assert_eq!(
            PhysicsParams::cwru(SimulatedFault::OuterRace)
                .unwrap()
                .validate(),
            Ok(())
        );
        let mut p = PhysicsParams::cwru(SimulatedFault::InnerRace).unwrap();
        p.rpm = f64::NAN;
        p.fs_hz = 10.0;
        p.defect_width_mm = -1.0;
        p.structure.resonator_stiffness = 0.0;
        let message = p.validate().unwrap_err().to_string();
        for needle in ["rpm NaN", "sample rate 10", "defect width -1", "k_r"] {
            assert!(message.contains(needle), "{message} lacks {needle}");
        }
    }

    #[test]
    fn default_resonator_rings_at_15_khz_with_5_percent_damping() {
        let s = PhysicsParams::cwru(SimulatedFault::None).unwrap().structure;
        assert!((s.resonance_hz() - 15_000.0).abs() < 10.0);
        assert!((s.resonator_damping_ratio() - 0.05).abs() < 1e-3);
    }
}
