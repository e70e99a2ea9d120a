//! Seeded random streams and the stochastic processes built on them.
//!
//! Every random quantity of a scenario draws from its own named [`Stream`]: a
//! `Pcg64Mcg` whose 128-bit state is a stable hash of (scenario seed, stream name).
//! Adding a stream therefore never changes the numbers of an existing one, and the
//! same seed gives the same numbers on every run. The hash is FNV-1a (name) mixed
//! with SplitMix64 (Steele, Lea & Flood 2014), not `std`'s `DefaultHasher`, whose
//! output may change between Rust releases.
//!
//! Reproducibility across platforms: the generator and the uniform conversion are
//! integer arithmetic. Normals use `rand_distr::StandardNormal` (ziggurat): its common
//! path is table look-ups and multiplications; about 1 % of draws fall in a wedge or
//! the tail and call `exp`/`ln` from the platform's libm, which IEEE 754 does not
//! require to be correctly rounded, so those rare draws could differ in the last bit
//! between libms. Same platform, same binary: byte-identical.

use rand::{Rng, RngExt, SeedableRng};
use rand_distr::StandardNormal;
use rand_pcg::Pcg64Mcg;

/// SplitMix64 finaliser (Steele, Lea & Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014).
#[inline]
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// 64-bit FNV-1a of the UTF-8 bytes (offset basis and prime from the FNV spec).
#[inline]
fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xCBF2_9CE4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01B3);
    }
    h
}

/// A named, seeded random stream (see the module documentation).
#[derive(Clone, Debug)]
pub struct Stream {
    rng: Pcg64Mcg,
}

impl Stream {
    /// The stream `name` of scenario `seed`.
    pub fn new(seed: u64, name: &str) -> Self {
        let k = splitmix64(seed) ^ fnv1a64(name.as_bytes());
        let lo = splitmix64(k);
        let hi = splitmix64(lo ^ 0x6A09_E667_F3BC_C909);
        let mut bytes = [0u8; 16];
        bytes[..8].copy_from_slice(&lo.to_le_bytes());
        bytes[8..].copy_from_slice(&hi.to_le_bytes());
        Self {
            rng: Pcg64Mcg::from_seed(bytes),
        }
    }

    /// A standard normal draw N(0, 1).
    #[inline]
    pub fn normal(&mut self) -> f64 {
        self.rng.sample(StandardNormal)
    }

    /// A uniform draw in [0, 1): the top 53 bits of one 64-bit output times 2^-53.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A uniform draw in [lo, hi) (returns `lo` when `hi <= lo`).
    #[inline]
    pub fn uniform_range(&mut self, lo: f64, hi: f64) -> f64 {
        if hi <= lo {
            return lo;
        }
        lo + (hi - lo) * self.uniform()
    }

    /// The next raw 64-bit output.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.rng.next_u64()
    }
}

/// First-order Gauss-Markov process with standard deviation `sigma` and correlation
/// time `tau_s`, exact discretisation
/// `x_{k+1} = e^{-dt/tau} x_k + sigma sqrt(1 - e^{-2 dt/tau}) w_k` (Maybeck 1979,
/// §4.11), started from its stationary distribution N(0, sigma²).
/// `tau_s = inf` gives a random constant, `sigma = 0` gives zero.
#[derive(Clone, Debug)]
pub struct GaussMarkov {
    sigma: f64,
    tau_s: f64,
    x: f64,
    /// Cached (dt, phi, drive std) for the last step size.
    cache: (f64, f64, f64),
}

impl GaussMarkov {
    /// A process in its stationary state (one draw from `rng` when `sigma > 0`).
    pub fn new(sigma: f64, tau_s: f64, rng: &mut Stream) -> Self {
        let x = if sigma > 0.0 {
            sigma * rng.normal()
        } else {
            0.0
        };
        Self {
            sigma,
            tau_s,
            x,
            cache: (f64::NAN, 1.0, 0.0),
        }
    }

    /// Advance by `dt_s` and return the new value. No draw is made when the process
    /// is constant (`sigma = 0` or `tau_s = inf`).
    #[inline]
    pub fn step(&mut self, dt_s: f64, rng: &mut Stream) -> f64 {
        if self.sigma == 0.0 || self.tau_s.is_infinite() {
            return self.x;
        }
        if dt_s != self.cache.0 {
            let phi = (-dt_s / self.tau_s).exp();
            let q = self.sigma * (1.0 - phi * phi).max(0.0).sqrt();
            self.cache = (dt_s, phi, q);
        }
        let (_, phi, q) = self.cache;
        self.x = phi * self.x + q * rng.normal();
        self.x
    }

    /// The current value.
    #[inline]
    pub fn value(&self) -> f64 {
        self.x
    }

    /// Standard deviation of the stationary distribution.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Correlation time \[s\].
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }
}

/// Random walk with white-noise PSD `q` (units²/s): `x += sqrt(q dt) w`.
#[derive(Clone, Debug)]
pub struct RandomWalk {
    q: f64,
    x: f64,
}

impl RandomWalk {
    /// A walk starting at `initial`.
    pub fn new(q: f64, initial: f64) -> Self {
        Self { q, x: initial }
    }

    /// Advance by `dt_s` and return the new value (no draw when `q = 0`).
    #[inline]
    pub fn step(&mut self, dt_s: f64, rng: &mut Stream) -> f64 {
        if self.q > 0.0 {
            self.x += (self.q * dt_s).sqrt() * rng.normal();
        }
        self.x
    }

    /// The current value.
    #[inline]
    pub fn value(&self) -> f64 {
        self.x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simulated_gm_matches_analytic_allan_curve() {
        use navfuse_core::allan::{allan_deviation, gauss_markov_adev};
        let (sigma, tau_c, dt) = (1.0, 2.0, 0.05);
        let mut rng = Stream::new(13, "adev.gm");
        let mut gm = GaussMarkov::new(sigma, tau_c, &mut rng);
        let y: Vec<f64> = (0..1_000_000).map(|_| gm.step(dt, &mut rng)).collect();
        let curve = allan_deviation(&y, dt, &[10, 40, 76, 200]);
        for (t, a) in curve {
            let expected = gauss_markov_adev(sigma, tau_c, t);
            // 50 000 s = 25 000 correlation times: a few % at most.
            assert!(
                (a / expected - 1.0).abs() < 0.05,
                "tau {t}: {a} vs {expected}"
            );
        }
    }

    #[test]
    fn stream_is_deterministic_and_names_differ() {
        let mut a = Stream::new(42, "imu.gyro.white");
        let mut b = Stream::new(42, "imu.gyro.white");
        let mut c = Stream::new(42, "imu.accel.white");
        let mut d = Stream::new(43, "imu.gyro.white");
        let va: Vec<u64> = (0..64).map(|_| a.next_u64()).collect();
        let vb: Vec<u64> = (0..64).map(|_| b.next_u64()).collect();
        let vc: Vec<u64> = (0..64).map(|_| c.next_u64()).collect();
        let vd: Vec<u64> = (0..64).map(|_| d.next_u64()).collect();
        assert_eq!(va, vb);
        assert!(va.iter().zip(&vc).all(|(x, y)| x != y));
        assert!(va.iter().zip(&vd).all(|(x, y)| x != y));
        // Normals and uniforms repeat bit for bit too.
        let mut a = Stream::new(7, "x");
        let mut b = Stream::new(7, "x");
        for _ in 0..1000 {
            assert_eq!(a.normal().to_bits(), b.normal().to_bits());
            assert_eq!(a.uniform().to_bits(), b.uniform().to_bits());
        }
    }

    #[test]
    fn stream_golden_values() {
        // Pins the seeding (FNV-1a + SplitMix64 -> Pcg64Mcg): a change here changes
        // every simulated scenario.
        let mut s = Stream::new(0, "golden");
        let got: Vec<u64> = (0..3).map(|_| s.next_u64()).collect();
        assert_eq!(got, GOLDEN.to_vec());
    }
    const GOLDEN: [u64; 3] = [
        17_257_893_048_765_385_848,
        12_967_040_976_945_272_647,
        4_399_958_919_445_642_771,
    ];

    #[test]
    fn uniform_moments_and_range() {
        let mut s = Stream::new(1, "u");
        let n = 200_000;
        let mut sum = 0.0;
        let mut sum2 = 0.0;
        for _ in 0..n {
            let u = s.uniform();
            assert!((0.0..1.0).contains(&u));
            sum += u;
            sum2 += u * u;
        }
        let mean = sum / n as f64;
        let var = sum2 / n as f64 - mean * mean;
        // Standard errors: 0.29/sqrt(n) = 6.5e-4 for the mean, ~2e-4 for the variance.
        assert!((mean - 0.5).abs() < 3e-3, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 1.5e-3, "var {var}");
        let r = s.uniform_range(-2.0, 3.0);
        assert!((-2.0..3.0).contains(&r));
        assert_eq!(s.uniform_range(1.0, 1.0), 1.0);
    }

    #[test]
    fn gauss_markov_stationary_variance_and_autocorrelation() {
        let (sigma, tau, dt) = (2.0, 5.0, 0.1);
        let mut rng = Stream::new(3, "gm");
        let mut gm = GaussMarkov::new(sigma, tau, &mut rng);
        let n = 400_000; // 40 000 s = 8 000 correlation times
        let lag = 50; // 5 s = one correlation time
        let mut xs = Vec::with_capacity(n);
        for _ in 0..n {
            xs.push(gm.step(dt, &mut rng));
        }
        let var = xs.iter().map(|x| x * x).sum::<f64>() / n as f64;
        let cov = xs.iter().zip(&xs[lag..]).map(|(a, b)| a * b).sum::<f64>() / (n - lag) as f64;
        let rho = cov / var;
        // Var of the variance estimate ~ 2 sigma^4 tau/T_record: 1.6 % standard error.
        assert!((var / (sigma * sigma) - 1.0).abs() < 0.06, "var {var}");
        // Expected e^-1 = 0.368; standard error about 0.012.
        assert!((rho - (-1.0f64).exp()).abs() < 0.04, "rho {rho}");
    }

    #[test]
    fn gauss_markov_starts_stationary() {
        // The first value across many seeds has variance sigma².
        let n = 20_000;
        let mut sum2 = 0.0;
        for seed in 0..n {
            let mut rng = Stream::new(seed, "gm0");
            let gm = GaussMarkov::new(3.0, 100.0, &mut rng);
            sum2 += gm.value() * gm.value();
        }
        let var = sum2 / n as f64;
        assert!((var / 9.0 - 1.0).abs() < 0.05, "var {var}");
    }

    #[test]
    fn gauss_markov_degenerate_cases() {
        let mut rng = Stream::new(5, "gm");
        let mut zero = GaussMarkov::new(0.0, 10.0, &mut rng);
        let mut constant = GaussMarkov::new(1.0, f64::INFINITY, &mut rng);
        let c0 = constant.value();
        assert!(c0 != 0.0);
        for _ in 0..100 {
            assert_eq!(zero.step(0.01, &mut rng), 0.0);
            assert_eq!(constant.step(0.01, &mut rng), c0);
        }
    }

    #[test]
    fn random_walk_variance_grows_linearly() {
        let (q, dt, steps, runs) = (0.5, 0.01, 1000, 4000);
        let mut rng = Stream::new(9, "rw");
        let mut sum2 = 0.0;
        for _ in 0..runs {
            let mut rw = RandomWalk::new(q, 1.0);
            for _ in 0..steps {
                rw.step(dt, &mut rng);
            }
            sum2 += (rw.value() - 1.0).powi(2);
        }
        let var = sum2 / runs as f64;
        let expected = q * dt * steps as f64; // 5.0
                                              // Standard error sqrt(2/4000) = 2.2 %.
        assert!((var / expected - 1.0).abs() < 0.08, "var {var}");
    }
}
