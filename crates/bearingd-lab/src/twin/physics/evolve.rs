//! A global optimiser for objectives that cost a simulation each (the physics twin's
//! calibration): differential evolution whose population is evaluated in parallel (rayon).
//! It lives with the physics twin, in the lab: the service's fits are local
//! (`crate::twin::optimize`) and need no thread pool.

/// Settings of [`differential_evolution`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvolutionSettings {
    /// Candidates per generation.
    pub population: usize,
    /// Generations after the initial population.
    pub generations: usize,
    /// Crossover probability `CR`.
    pub crossover: f64,
    /// Stop early when the population's values span less than this fraction of the best.
    pub tolerance: f64,
    pub seed: u64,
}

/// Where [`differential_evolution`] stands after a generation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvolutionProgress<const N: usize> {
    /// 0 for the initial population.
    pub generation: usize,
    pub best: [f64; N],
    pub best_value: f64,
    pub evaluations: usize,
}

/// Minimises `f` over `[0, 1]^N` by differential evolution (Storn & Price 1997), strategy
/// DE/rand-to-best/1/bin with the scale factor dithered per generation in [0.5, 1): a global
/// method that needs no gradient and no starting point, copes with the several local minima
/// a spectral misfit has, and evaluates a whole generation at once, so the evaluations run in
/// parallel on every core (rayon). The trial points are drawn on the calling thread from
/// `seed`, so the result does not depend on the number of threads. `progress` is called on the
/// calling thread after every generation. `guesses` (clamped to the cube) replace the first
/// members of the initial population: a cheap heuristic start the evolution can build on or
/// discard. Returns the last progress (best point, its value, evaluations).
pub fn differential_evolution<const N: usize>(
    settings: &EvolutionSettings,
    guesses: &[[f64; N]],
    f: impl Fn(&[f64; N]) -> f64 + Sync,
    mut progress: impl FnMut(&EvolutionProgress<N>),
) -> EvolutionProgress<N> {
    use rayon::prelude::*;
    let size = settings.population.max(4);
    let mut rng = crate::random::Rng::new(settings.seed);
    let evaluate = |points: &[[f64; N]]| -> Vec<f64> {
        points
            .par_iter()
            .map(|p| {
                let v = f(p);
                if v.is_finite() {
                    v
                } else {
                    f64::MAX
                }
            })
            .collect()
    };
    // Initial population: a Latin hypercube (each coordinate's strata used once).
    let mut points = vec![[0.0; N]; size];
    for d in 0..N {
        let mut strata: Vec<usize> = (0..size).collect();
        for i in (1..size).rev() {
            strata.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        for (point, stratum) in points.iter_mut().zip(strata) {
            point[d] = (stratum as f64 + rng.uniform()) / size as f64;
        }
    }
    for (point, guess) in points.iter_mut().zip(guesses) {
        *point = guess.map(|v| v.clamp(0.0, 1.0));
    }
    let mut values = evaluate(&points);
    let mut evaluations = size;
    let best_of = |points: &[[f64; N]], values: &[f64]| {
        let i = (0..values.len())
            .min_by(|&a, &b| values[a].total_cmp(&values[b]))
            .unwrap_or(0);
        (points[i], values[i])
    };
    let (best, best_value) = best_of(&points, &values);
    let mut state = EvolutionProgress {
        generation: 0,
        best,
        best_value,
        evaluations,
    };
    progress(&state);
    let pick = |rng: &mut crate::random::Rng, not: &[usize]| loop {
        let i = (rng.next_u64() % size as u64) as usize;
        if !not.contains(&i) {
            return i;
        }
    };
    for generation in 1..=settings.generations {
        let scale = 0.5 + 0.5 * rng.uniform();
        let trials: Vec<[f64; N]> = (0..size)
            .map(|i| {
                let a = pick(&mut rng, &[i]);
                let b = pick(&mut rng, &[i, a]);
                let forced = (rng.next_u64() % N as u64) as usize;
                let parent = points[i];
                let mut trial = parent;
                for (d, coordinate) in trial.iter_mut().enumerate() {
                    if d == forced || rng.uniform() < settings.crossover {
                        let v = parent[d]
                            + scale * (state.best[d] - parent[d])
                            + scale * (points[a][d] - points[b][d]);
                        // Out of the cube: halfway back to the parent's coordinate.
                        *coordinate = if v < 0.0 {
                            parent[d] / 2.0
                        } else if v > 1.0 {
                            (parent[d] + 1.0) / 2.0
                        } else {
                            v
                        };
                    }
                }
                trial
            })
            .collect();
        let trial_values = evaluate(&trials);
        evaluations += size;
        for ((point, value), (trial, trial_value)) in points
            .iter_mut()
            .zip(values.iter_mut())
            .zip(trials.iter().zip(&trial_values))
        {
            if trial_value <= value {
                *point = *trial;
                *value = *trial_value;
            }
        }
        let (best, best_value) = best_of(&points, &values);
        state = EvolutionProgress {
            generation,
            best,
            best_value,
            evaluations,
        };
        progress(&state);
        let worst = values.iter().copied().fold(f64::MIN, f64::max);
        if worst - best_value <= settings.tolerance * best_value.abs() {
            break;
        }
    }
    state
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differential_evolution_finds_the_global_minimum_of_a_multimodal_function() {
        // Rastrigin-like in 3-D on the cube, global minimum 0 at (0.3, 0.6, 0.8), many local
        // minima 0.1 apart.
        let target = [0.3, 0.6, 0.8];
        let f = |p: &[f64; 3]| {
            p.iter()
                .zip(&target)
                .map(|(x, t)| {
                    let u = 10.0 * (x - t);
                    u * u + 3.0 * (1.0 - (std::f64::consts::TAU * u).cos())
                })
                .sum::<f64>()
        };
        let settings = EvolutionSettings {
            population: 30,
            generations: 200,
            crossover: 0.9,
            tolerance: 1e-9,
            seed: 3,
        };
        let mut generations = 0;
        let result = differential_evolution(&settings, &[], f, |p| generations = p.generation);
        assert!(result.best_value < 1e-4, "{result:?}");
        for (x, t) in result.best.iter().zip(&target) {
            assert!((x - t).abs() < 1e-3, "{result:?}");
        }
        assert_eq!(result.evaluations, 30 * (generations + 1));
        // The same seed gives the same answer, whatever the threads did.
        let again = differential_evolution(&settings, &[], f, |_| {});
        assert_eq!(again, result);
    }
}
