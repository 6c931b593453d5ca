//! The per-pixel sums a render accumulates, and what they tell: means, variances, dropped
//! samples and the estimated error.

pub use crate::scene::records::accum_entries as entries_per_pixel;

/// Per-pixel sums of samples, [`Accumulation::entries`] `[f32; 4]` per pixel i (row-major
/// from the top-left) from `data[entries * i]`: (sum r, sum g, sum b, count), (sum r^2,
/// sum g^2, sum b^2, samples dropped as not finite), and with `aovs` (sum albedo rgb, sum
/// depth), (sum normal xyz, 0), (sum position xyz, 0) over every sample, dropped or not.
///
/// A render that splats (`[render] reconstruction = "splat"`) sums each sample into every
/// pixel its filter reaches with its weight w there: (sum w L, sum w), (sum w L^2,
/// dropped), and its AOVs into its own pixel, their count in the normal's fourth
/// component. Its mean is sum w L / sum w; its variance and error estimates take sum w
/// for the count (for Mitsuba's Gaussian, about 2x the true variance of the mean).
#[derive(Debug, Clone, PartialEq)]
pub struct Accumulation {
    pub width: u32,
    pub height: u32,
    /// Whether the sums hold the AOVs (`crate::aov`).
    pub aovs: bool,
    pub data: Vec<[f32; 4]>,
}

impl Accumulation {
    /// Sums of no samples.
    pub fn zeros(width: u32, height: u32, aovs: bool) -> Self {
        let n = width as usize * height as usize * entries_per_pixel(aovs);
        Accumulation {
            width,
            height,
            aovs,
            data: vec![[0.0; 4]; n],
        }
    }

    /// What a render under `--tune lane-stats` summed instead of light
    /// (`gpu::plan::LANE_STATS`): per kind of step (a turn of the bounce loop, a BVH node
    /// step, a primitive test), the share of the subgroups' lanes that took part in its
    /// steps, and the lane steps per sample.
    pub fn lane_shares(&self) -> ([f64; 3], [f64; 3]) {
        let entries = self.entries();
        let (mut steps, mut shares, mut samples) = ([0f64; 3], [0f64; 3], 0f64);
        for pixel in self.data.chunks(entries) {
            for k in 0..3 {
                steps[k] += pixel[0][k] as f64;
                shares[k] += pixel[1][k] as f64;
            }
            samples += pixel[0][3] as f64;
        }
        (
            std::array::from_fn(|k| steps[k] / shares[k].max(f64::MIN_POSITIVE)),
            std::array::from_fn(|k| steps[k] / samples.max(1.0)),
        )
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// `[f32; 4]` entries per pixel.
    pub fn entries(&self) -> usize {
        entries_per_pixel(self.aovs)
    }

    /// Entry `k` of pixel `i`.
    fn entry(&self, i: usize, k: usize) -> [f32; 4] {
        self.data[self.entries() * i + k]
    }

    /// Samples accumulated in pixel `i`.
    pub fn samples(&self, i: usize) -> f32 {
        self.entry(i, 0)[3]
    }

    /// Mean radiance of pixel `i`.
    pub fn mean(&self, i: usize) -> [f32; 3] {
        let s = self.entry(i, 0);
        // a count, or a splat render's sum of weights (which may be below 1)
        let n = if s[3] > 0.0 { s[3] } else { 1.0 };
        [s[0] / n, s[1] / n, s[2] / n]
    }

    /// The mean of AOV entry `k` (2: albedo and depth, 3: normal, 4: position) of pixel
    /// `i` over every sample, those dropped from the colour as not finite too; zeros
    /// without AOVs.
    pub fn aov_mean(&self, i: usize, k: usize) -> [f32; 4] {
        if !self.aovs {
            return [0.0; 4];
        }
        // a splat render counts the samples in the normal's fourth component (its colour's
        // count is a sum of weights)
        let counted = self.entry(i, 3)[3];
        let n = if counted > 0.0 {
            counted
        } else {
            (self.entry(i, 0)[3] + self.entry(i, 1)[3]).max(1.0)
        };
        let mut mean = self.entry(i, k).map(|x| x / n);
        if k == 3 {
            mean[3] = 0.0;
        }
        mean
    }

    /// Unbiased sample variance of one sample of pixel `i`, per channel.
    pub fn variance(&self, i: usize) -> [f32; 3] {
        let s = self.entry(i, 0);
        let q = self.entry(i, 1);
        let n = s[3];
        if n < 2.0 {
            return [0.0; 3];
        }
        std::array::from_fn(|c| ((q[c] - s[c] * s[c] / n) / (n - 1.0)).max(0.0))
    }

    /// Samples dropped because they were not finite (NaN or infinite), over all pixels.
    pub fn non_finite(&self) -> u64 {
        (0..self.pixel_count())
            .map(|i| self.entry(i, 1)[3] as u64)
            .sum()
    }

    /// Mean radiance of every pixel, as `width * height * 3` linear floats.
    pub fn to_rgb(&self) -> Vec<f32> {
        (0..self.pixel_count()).flat_map(|i| self.mean(i)).collect()
    }

    /// Estimated relative squared error of pixel `i`'s mean, averaged over its channels:
    /// (variance / n) / (mean^2 + 0.01), the relative MSE of the convergence reports with
    /// the unknown true value replaced by the mean. Unbiased for independent samples;
    /// the low-discrepancy samplers converge faster than the variance says, so for them
    /// it is an overestimate.
    pub fn pixel_rel_mse(&self, i: usize) -> f64 {
        let (m, v, n) = (
            self.mean(i),
            self.variance(i),
            self.samples(i).max(1.0) as f64,
        );
        (0..3)
            .map(|c| v[c] as f64 / n / ((m[c] as f64).powi(2) + REL_MSE_EPSILON))
            .sum::<f64>()
            / 3.0
    }

    /// Estimated relative MSE of the whole image (`pixel_rel_mse` averaged over pixels).
    pub fn estimated_rel_mse(&self) -> f64 {
        (0..self.pixel_count())
            .map(|i| self.pixel_rel_mse(i))
            .sum::<f64>()
            / self.pixel_count().max(1) as f64
    }

    /// Estimated relative error: the square root of `estimated_rel_mse`.
    pub fn estimated_rel_error(&self) -> f64 {
        self.estimated_rel_mse().sqrt()
    }
}

/// The 0.01 in relative MSE, mean((x - r)^2 / (r^2 + 0.01)): keeps black pixels from
/// dominating.
pub const REL_MSE_EPSILON: f64 = 0.01;
