//! The photons of each SPPM iteration when the scene does not set `photons`.
//!
//! An iteration has a part whose cost is fixed by the image, the camera pass (one camera
//! sample per pixel, about [`RAYS_PER_CAMERA_SAMPLE`] ray casts), and a part the renderer can
//! size, the photons (each as many ray casts as it has segments), which also pay for the extra
//! camera samples of the emitted and directly lit light (`balance.rs`: a third of their ray
//! casts). Too few photons per iteration and the fixed camera pass dominates the time, no
//! extra camera sample is paid for, and the radii (which shrink by iteration, whatever the
//! photon count) shrink faster than the photons gathered can follow: noise. Too many and the
//! visible points (anti-aliasing, depth of field, a glass surface's branches) are sampled too
//! rarely, and the radii stay large: blur. The rule: the photon pass casts [`PHOTON_RAYS`]
//! times the rays of the camera pass's one sample per pixel, so photons get two thirds of
//! the first pass's casts and every pixel one extra camera sample on average:
//!
//! `N = PHOTON_RAYS * RAYS_PER_CAMERA_SAMPLE * pixels / segments per photon`,
//!
//! the segments per photon counted over all photons so far (the first iteration assumes
//! [`FIRST_SEGMENTS`]), in whole chunks of [`CHUNK`] photons. Where the camera part's noise
//! outweighs the photons' (`balance.rs`), the camera pass casts `ratio > 1` times the photon
//! pass's rays, and the photons get `2 / (1 + ratio)` of that count: the two passes' casts
//! together stay twice the count's. On the Cornell box at 256 x 256
//! (1.9 segments per photon) that is about 200 000 photons, the count chosen there by hand;
//! at a quarter of the resolution it is a quarter of that, and a scene whose photons bounce
//! longer gets fewer. Only counts enter: the same on any thread count and machine load.

use crate::integrators::common::camera_samples::RAYS_PER_CAMERA_SAMPLE;

/// Photons per iteration are whole multiples of this (the photon pass's task size).
const CHUNK: u64 = 4096;

/// The photon pass's ray casts over those of one camera sample per pixel.
const PHOTON_RAYS: f64 = 2.0;

/// Segments per photon assumed before any photon was traced.
const FIRST_SEGMENTS: f64 = 2.0;

/// The photon count of every iteration: the scene's, or the automatic rule's.
pub(super) struct PhotonCount {
    fixed: Option<u64>,
    pixels: u64,
    /// Photons traced and their segments, over the whole render.
    photons: u64,
    segments: u64,
    /// The camera pass's ray casts over the photon pass's.
    camera_ratio: f64,
}

impl PhotonCount {
    /// `fixed`: the scene's count; `None`: chosen every iteration for `pixels` pixels.
    pub(super) fn new(fixed: Option<u64>, pixels: usize) -> Self {
        PhotonCount {
            fixed,
            pixels: pixels as u64,
            photons: 0,
            segments: 0,
            camera_ratio: 1.0,
        }
    }

    /// Photons of the coming iteration.
    pub(super) fn next(&self) -> u64 {
        self.fixed.unwrap_or_else(|| {
            let segments = self.segments_per_photon();
            // The photons' share of the two passes' casts: half of them while the camera pass
            // casts as many (ratio 1, [`super::balance::camera_share`]).
            let share = 2.0 / (1.0 + self.camera_ratio);
            let rays = share * PHOTON_RAYS * RAYS_PER_CAMERA_SAMPLE * self.pixels as f64;
            whole_chunks(rays / segments)
        })
    }

    /// The segments per photon counted so far (the first iteration's assumption before any).
    pub(super) fn segments_per_photon(&self) -> f64 {
        if self.photons == 0 {
            FIRST_SEGMENTS
        } else {
            // A photon that leaves the scene at once still cast a ray.
            (self.segments as f64 / self.photons as f64).max(1.0)
        }
    }

    /// Sets the ratio of the camera pass's ray casts to the photon pass's
    /// ([`super::balance::camera_share`]); 1 until set.
    pub(super) fn set_camera_ratio(&mut self, ratio: f64) {
        self.camera_ratio = ratio;
    }

    /// After an iteration of `photons` photons whose pass cast `segments` rays.
    pub(super) fn record(&mut self, photons: u64, segments: u64) {
        self.photons = self.photons.saturating_add(photons);
        self.segments = self.segments.saturating_add(segments);
    }
}

/// `n` rounded to whole chunks, at least one, at most 2^40 photons.
fn whole_chunks(n: f64) -> u64 {
    let chunks = (n / CHUNK as f64).round().clamp(1.0, (1u64 << 28) as f64);
    chunks as u64 * CHUNK
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scene's count stays; the automatic one follows the pixels and the measured
    /// segments per photon.
    #[test]
    fn the_count_follows_the_pixels_and_the_segments_per_photon() {
        let mut fixed = PhotonCount::new(Some(1234), 65_536);
        fixed.record(1234, 100_000);
        assert_eq!(fixed.next(), 1234);
        // 256 x 256 pixels: 2 x 3 x 65 536 rays, 2 segments per photon at first.
        let mut auto = PhotonCount::new(None, 65_536);
        assert_eq!(auto.next(), 196_608);
        // 1.5 segments per photon measured: more photons.
        auto.record(196_608, 294_912);
        assert_eq!(auto.next(), 262_144);
        // A quarter of the pixels, a quarter of the photons.
        assert_eq!(PhotonCount::new(None, 16_384).next(), 49_152);
        // Photons that leave at once count one ray each.
        auto.record(10_000_000, 0);
        assert_eq!(auto.next(), 393_216);
        // Tiny images trace one chunk.
        assert_eq!(PhotonCount::new(None, 4).next(), CHUNK);
        assert_eq!(whole_chunks(f64::INFINITY), 1 << 40);
    }
}
