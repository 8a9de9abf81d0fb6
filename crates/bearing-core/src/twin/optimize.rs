//! Small derivative-free optimisers for the twin fits: a Nelder–Mead simplex on the unit cube
//! (bounds by construction) and a golden-section line search, both local, taking the objective
//! as a closure, counting evaluations and not allocating per evaluation. (The global
//! differential evolution of the physics twin's calibration, evaluated in parallel, is the lab's:
//! `bearingd_lab::twin::physics::evolve`.)

/// Minimises `f` over `[0, 1]^N` starting around `start`; returns the best point, its value
/// and the number of evaluations.
pub fn nelder_mead<const N: usize>(
    start: [f64; N],
    initial_step: f64,
    max_evaluations: usize,
    tolerance: f64,
    mut f: impl FnMut(&[f64; N]) -> f64,
) -> ([f64; N], f64, usize) {
    let clamp = |p: [f64; N]| p.map(|v| v.clamp(0.0, 1.0));
    let mut evaluations = 0;
    let mut eval = |p: &[f64; N], evaluations: &mut usize| {
        *evaluations += 1;
        let v = f(p);
        if v.is_finite() {
            v
        } else {
            f64::MAX
        }
    };
    // N + 1 vertices; N ≤ 8 in practice, so a fixed-size array would be nicer but const
    // generic arithmetic is not stable: a small Vec allocated once per optimisation.
    let mut simplex: Vec<([f64; N], f64)> = Vec::with_capacity(N + 1);
    let first = clamp(start);
    simplex.push((first, eval(&first, &mut evaluations)));
    for i in 0..N {
        let mut p = first;
        p[i] = if p[i] + initial_step <= 1.0 {
            p[i] + initial_step
        } else {
            p[i] - initial_step
        };
        simplex.push((p, eval(&p, &mut evaluations)));
    }
    while evaluations < max_evaluations {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (best, worst) = (simplex[0].1, simplex[N].1);
        if (worst - best).abs() <= tolerance * (best.abs() + tolerance) {
            break;
        }
        let mut centroid = [0.0; N];
        for (p, _) in &simplex[..N] {
            for (c, v) in centroid.iter_mut().zip(p) {
                *c += v / N as f64;
            }
        }
        let worst_point = simplex[N].0;
        let along = |t: f64| {
            let mut p = centroid;
            for (v, w) in p.iter_mut().zip(&worst_point) {
                *v += t * (w - *v);
            }
            clamp(p)
        };
        let reflected = along(-1.0);
        let reflected_value = eval(&reflected, &mut evaluations);
        if reflected_value < simplex[0].1 {
            let expanded = along(-2.0);
            let expanded_value = eval(&expanded, &mut evaluations);
            simplex[N] = if expanded_value < reflected_value {
                (expanded, expanded_value)
            } else {
                (reflected, reflected_value)
            };
        } else if reflected_value < simplex[N - 1].1 {
            simplex[N] = (reflected, reflected_value);
        } else {
            let contracted = along(if reflected_value < simplex[N].1 {
                -0.5
            } else {
                0.5
            });
            let contracted_value = eval(&contracted, &mut evaluations);
            if contracted_value < simplex[N].1.min(reflected_value) {
                simplex[N] = (contracted, contracted_value);
            } else {
                let best_point = simplex[0].0;
                for vertex in simplex.iter_mut().skip(1) {
                    for (v, b) in vertex.0.iter_mut().zip(&best_point) {
                        *v = b + 0.5 * (*v - b);
                    }
                    vertex.1 = eval(&vertex.0, &mut evaluations);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    (simplex[0].0, simplex[0].1, evaluations)
}

/// Golden-section search for the minimum of a unimodal `f` on `[lo, hi]`.
pub fn golden_section(
    mut lo: f64,
    mut hi: f64,
    iterations: usize,
    mut f: impl FnMut(f64) -> f64,
) -> (f64, f64) {
    const INVERSE_PHI: f64 = 0.618_033_988_749_894_9;
    let mut x1 = hi - INVERSE_PHI * (hi - lo);
    let mut x2 = lo + INVERSE_PHI * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iterations {
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - INVERSE_PHI * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + INVERSE_PHI * (hi - lo);
            f2 = f(x2);
        }
    }
    if f1 <= f2 {
        (x1, f1)
    } else {
        (x2, f2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nelder_mead_finds_a_shifted_quadratic_minimum_inside_the_cube() {
        let (p, v, n) = nelder_mead([0.5, 0.5, 0.5], 0.2, 2_000, 1e-12, |p| {
            (p[0] - 0.2).powi(2) + 3.0 * (p[1] - 0.7).powi(2) + (p[2] - 0.9).powi(2)
        });
        assert!(v < 1e-8 && n < 2_000, "{p:?} {v} {n}");
        assert!(
            (p[0] - 0.2).abs() < 1e-3 && (p[1] - 0.7).abs() < 1e-3 && (p[2] - 0.9).abs() < 1e-3
        );
    }

    #[test]
    fn nelder_mead_respects_the_bounds() {
        let (p, _, _) = nelder_mead([0.5, 0.5], 0.2, 500, 1e-12, |p| -p[0] + p[1]);
        assert!(p[0] > 0.999 && p[1] < 0.001, "{p:?}");
    }

    #[test]
    fn golden_section_finds_the_minimum() {
        let (x, _) = golden_section(0.0, 10.0, 60, |x| (x - 3.3).powi(2));
        assert!((x - 3.3).abs() < 1e-6);
    }
}
