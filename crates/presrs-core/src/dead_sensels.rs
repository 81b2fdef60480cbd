//! Dead-sensel detection: a sensel that never responds while its neighbours do.
//!
//! A present sensel is reported dead when it reads 0 in every frame of a recording and, in at least
//! [`DeadSenselConfig::min_frames`] frames, it is *surrounded* by load: every present 4-neighbour
//! (up, down, left, right) and at least [`DeadSenselConfig::neighbour_fraction`] of its present
//! 8-neighbours (and at least three of them) read more than 0. A sensel on the edge of the contact area
//! has an unloaded neighbour on its outer side and is not surrounded, and a sensel that is never near
//! the load is never surrounded: neither is reported.
//!
//! **Edge sensels.** A sensel without a present neighbour on each of its four sides — on the border of
//! the array, or next to an absent sensel — cannot be seen surrounded: the load may end just beyond it
//! (a contact cut by the array's border reads 0 there too). It is reported only on stronger evidence:
//! at least three present sides, *every* present neighbour (all of its five, or fewer) loaded, in at
//! least twice `min_frames` frames (6 by default; every frame of a shorter recording). A corner sensel
//! (two sides) is never reported. A recording of fewer frames than `min_frames` asks every present
//! neighbour to be loaded in every frame.
//!
//! [`correct_dead_sensels`] detects and fills them (each frame, from the sensel's present, live
//! neighbours, with [`crate::preprocess::fill_dead_sensels`]); `presrs` does so for every recording it
//! reads from a file unless told `--keep-dead-sensels`. It corrects recordings of at least
//! `min_frames` frames only: in one image a sensel reading 0 amid load may just be a gap in the
//! terrain's texture, whereas a sensel silent through several frames of load is a fault.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::preprocess::{FillScratch, fill_dead_sensels};
use crate::recording::Recording;

/// Thresholds of [`detect_dead_sensels`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeadSenselConfig {
    /// Frames in which the sensel must be surrounded by load.
    pub min_frames: usize,
    /// Fraction of the present neighbours that must carry load for the sensel to count as surrounded.
    pub neighbour_fraction: f64,
}

impl Default for DeadSenselConfig {
    fn default() -> Self {
        Self {
            min_frames: 3,
            neighbour_fraction: 0.75,
        }
    }
}

/// How many times `min_frames` an edge sensel (a side without a present neighbour) must be surrounded.
const EDGE_EVIDENCE: usize = 2;

/// A sensel found dead.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeadSensel {
    /// 0-based row and column.
    pub row: usize,
    pub col: usize,
    /// Frames in which its neighbours carried load around it while it read 0.
    pub surrounded_frames: usize,
}

/// The dead sensels of `recording`, in row-major order (see the module documentation).
pub fn detect_dead_sensels(recording: &Recording, config: &DeadSenselConfig) -> Vec<DeadSensel> {
    let grid = recording.grid();
    let (rows, cols) = (grid.rows, grid.cols);
    let cells = grid.len();
    let frames = recording.frame_count();
    if cells == 0 || frames == 0 {
        return Vec::new();
    }
    let data = recording.data();
    let present = |i: usize| recording.present().is_none_or(|p| p[i]);
    // Sensels that read 0 in every frame.
    let mut silent: Vec<bool> = (0..cells).map(present).collect();
    for frame in data.chunks_exact(cells) {
        for (quiet, &v) in silent.iter_mut().zip(frame) {
            if v != 0.0 {
                *quiet = false;
            }
        }
    }
    let (min_frames, fraction) = if frames < config.min_frames {
        (frames, 1.0)
    } else {
        (config.min_frames.max(1), config.neighbour_fraction)
    };
    let mut found = Vec::new();
    for i in (0..cells).filter(|&i| silent[i]) {
        let (r, c) = (i / cols, i % cols);
        let neighbours: Vec<usize> = (r.saturating_sub(1)..=(r + 1).min(rows - 1))
            .flat_map(|nr| {
                (c.saturating_sub(1)..=(c + 1).min(cols - 1)).map(move |nc| nr * cols + nc)
            })
            .filter(|&n| n != i && present(n))
            .collect();
        if neighbours.len() < 3 {
            continue;
        }
        // The present 4-neighbours: every one of them must be loaded.
        let sides: Vec<usize> = neighbours
            .iter()
            .copied()
            .filter(|&n| n / cols == r || n % cols == c)
            .collect();
        // An edge sensel (a side missing) needs every neighbour loaded, in more frames.
        let (needed, frames_needed) = match sides.len() {
            4 => (
                ((fraction * neighbours.len() as f64).ceil() as usize).max(3),
                min_frames,
            ),
            3 => (neighbours.len(), (EDGE_EVIDENCE * min_frames).min(frames)),
            _ => continue,
        };
        let surrounded_frames = data
            .chunks_exact(cells)
            .filter(|frame| {
                sides.iter().all(|&n| frame[n] > 0.0)
                    && neighbours.iter().filter(|&&n| frame[n] > 0.0).count() >= needed
            })
            .count();
        if surrounded_frames >= frames_needed {
            found.push(DeadSensel {
                row: r,
                col: c,
                surrounded_frames,
            });
        }
    }
    found
}

/// Whether [`correct_dead_sensels`] corrects a recording of `frames` frames under `config`: it needs
/// at least `min_frames` frames (a single image is not evidence enough; see the module documentation).
pub fn correctable(frames: usize, config: &DeadSenselConfig) -> bool {
    frames >= config.min_frames.max(1)
}

/// Detects the dead sensels of `recording` ([`detect_dead_sensels`]) and fills them in every frame from
/// their present, live neighbours. Returns the recording (unchanged when none is found or when it has
/// too few frames, see [`correctable`]) and the sensels filled.
pub fn correct_dead_sensels(
    recording: Recording,
    config: &DeadSenselConfig,
) -> Result<(Recording, Vec<DeadSensel>)> {
    if !correctable(recording.frame_count(), config) {
        return Ok((recording, Vec::new()));
    }
    let dead = detect_dead_sensels(&recording, config);
    if dead.is_empty() {
        return Ok((recording, dead));
    }
    let grid = recording.grid();
    let mut mask = vec![false; grid.len()];
    for d in &dead {
        mask[d.row * grid.cols + d.col] = true;
    }
    let mut data = recording.data().to_vec();
    let mut scratch = FillScratch::new(grid.len());
    for frame in data.chunks_exact_mut(grid.len()) {
        fill_dead_sensels(frame, grid, recording.present(), &mask, &mut scratch)?;
    }
    let corrected = Recording::with_info(
        grid,
        recording.frame_period_s(),
        data,
        recording.present().map(<[bool]>::to_vec),
        recording.frame_info().to_vec(),
        recording.meta.clone(),
    )?;
    Ok((corrected, dead))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Grid;
    use crate::recording::SensorMeta;

    /// `frames` frames of a 12 x 12 grid with a loaded disc (radius 3.5 around (5, 5)) in frames 2..,
    /// frame 0 and 1 unloaded.
    fn disc_movie(frames: usize) -> Vec<f64> {
        let mut data = Vec::new();
        for f in 0..frames {
            for r in 0..12 {
                for c in 0..12 {
                    let d2 = (r as f64 - 5.0).powi(2) + (c as f64 - 5.0).powi(2);
                    let loaded = f >= 2 && d2 <= 3.5f64.powi(2);
                    data.push(if loaded { 10.0 + f as f64 } else { 0.0 });
                }
            }
        }
        data
    }

    fn movie(data: Vec<f64>, frames: usize, present: Option<Vec<bool>>) -> Recording {
        assert_eq!(data.len(), frames * 144);
        Recording::new(
            Grid::new(12, 12),
            Some(0.01),
            data,
            present,
            SensorMeta::default(),
        )
        .unwrap()
    }

    fn kill(data: &mut [f64], r: usize, c: usize) {
        for frame in data.chunks_exact_mut(144) {
            frame[r * 12 + c] = 0.0;
        }
    }

    #[test]
    fn finds_a_silent_sensel_inside_the_load_only() {
        let mut data = disc_movie(8);
        kill(&mut data, 5, 5); // the centre
        kill(&mut data, 4, 7); // inside, off centre
        kill(&mut data, 5, 8); // on the rim: neighbours loaded on one side only
        let rec = movie(data, 8, None);
        let dead = detect_dead_sensels(&rec, &DeadSenselConfig::default());
        let at: Vec<(usize, usize)> = dead.iter().map(|d| (d.row, d.col)).collect();
        assert_eq!(at, [(4, 7), (5, 5)]);
        assert_eq!(dead[1].surrounded_frames, 6);
    }

    #[test]
    fn a_clean_recording_or_too_few_loaded_frames_has_none() {
        let rec = movie(disc_movie(8), 8, None);
        assert!(detect_dead_sensels(&rec, &DeadSenselConfig::default()).is_empty());
        // Loaded in only 2 frames (2 and 3 of 4): fewer than min_frames = 3.
        let mut data = disc_movie(4);
        kill(&mut data, 5, 5);
        let rec = movie(data, 4, None);
        assert!(detect_dead_sensels(&rec, &DeadSenselConfig::default()).is_empty());
        let lax = DeadSenselConfig {
            min_frames: 2,
            ..DeadSenselConfig::default()
        };
        assert_eq!(detect_dead_sensels(&rec, &lax).len(), 1);
    }

    #[test]
    fn absent_sensels_are_neither_dead_nor_counted_as_neighbours() {
        let mut data = disc_movie(6);
        kill(&mut data, 5, 5);
        let mut present = vec![true; 144];
        present[5 * 12 + 5] = false; // the silent sensel is outside the sensor: not dead
        let rec = movie(data.clone(), 6, Some(present));
        assert!(detect_dead_sensels(&rec, &DeadSenselConfig::default()).is_empty());
        // Absent neighbours do not count against a dead sensel; but with a side absent ((4, 5) above
        // it) it is an edge sensel, reported on twice the evidence: 4 loaded frames are not enough, 8 are.
        let mut present = vec![true; 144];
        present[4 * 12 + 4] = false;
        present[4 * 12 + 5] = false;
        let rec = movie(data, 6, Some(present.clone()));
        assert!(detect_dead_sensels(&rec, &DeadSenselConfig::default()).is_empty());
        let mut data = disc_movie(10);
        kill(&mut data, 5, 5);
        let rec = movie(data, 10, Some(present));
        let dead = detect_dead_sensels(&rec, &DeadSenselConfig::default());
        assert_eq!(dead.len(), 1);
        assert_eq!((dead[0].row, dead[0].col), (5, 5));
    }

    #[test]
    fn a_single_image_needs_every_neighbour_loaded() {
        let mut data = disc_movie(3)[2 * 144..].to_vec();
        kill(&mut data, 5, 5);
        kill(&mut data, 5, 8);
        let rec = movie(data, 1, None);
        let dead = detect_dead_sensels(&rec, &DeadSenselConfig::default());
        assert_eq!(
            dead,
            [DeadSensel {
                row: 5,
                col: 5,
                surrounded_frames: 1
            }]
        );
    }

    #[test]
    fn a_contact_edge_on_the_array_border_is_not_dead() {
        // Load over rows 0..6, columns 0..=4 + 2 r: a diagonal edge. (0, 5) is silent, on the border
        // row, with four of its five neighbours loaded ((0, 4), (1, 4), (1, 5), (1, 6)).
        let mut data = Vec::new();
        for _ in 0..6 {
            for r in 0..12 {
                for c in 0..12 {
                    data.push(if r < 6 && c <= 4 + 2 * r { 20.0 } else { 0.0 });
                }
            }
        }
        let rec = movie(data, 6, None);
        assert!(detect_dead_sensels(&rec, &DeadSenselConfig::default()).is_empty());
    }

    #[test]
    fn correction_fills_dead_sensels_from_their_neighbours_only() {
        // A smooth load (a paraboloid) so that the neighbours' mean is close to the true value.
        let value = |f: usize, r: usize, c: usize| {
            let d2 = (r as f64 - 5.0).powi(2) + (c as f64 - 5.0).powi(2);
            if f >= 2 && d2 <= 12.25 {
                100.0 - 4.0 * d2
            } else {
                0.0
            }
        };
        let mut data = Vec::new();
        for f in 0..8 {
            for r in 0..12 {
                for c in 0..12 {
                    data.push(value(f, r, c));
                }
            }
        }
        let clean = data.clone();
        kill(&mut data, 4, 5); // inside: dead
        kill(&mut data, 5, 8); // on the rim (5, 8): 100 - 36 = 64 in the clean image, not dead
        let mut present = vec![true; 144];
        present[11 * 12 + 11] = false;
        let rec = movie(data.clone(), 8, Some(present));
        let (fixed, dead) = correct_dead_sensels(rec, &DeadSenselConfig::default()).unwrap();
        assert_eq!(
            dead.iter().map(|d| (d.row, d.col)).collect::<Vec<_>>(),
            [(4, 5)]
        );
        for f in 0..8 {
            let frame = fixed.frame(f).unwrap();
            let truth = clean[f * 144 + 4 * 12 + 5];
            // The mean of the 4-neighbours of a paraboloid: the true value plus its curvature (4).
            assert!((frame.get(4, 5) - truth).abs() <= 4.0 + 1e-9, "{f}");
            assert_eq!(frame.get(5, 8), 0.0, "the rim sensel is left alone");
            for i in (0..144).filter(|&i| i != 4 * 12 + 5) {
                assert_eq!(frame.values()[i], data[f * 144 + i], "{f} {i}");
            }
        }
        assert_eq!(
            fixed.present(),
            Some(
                &{
                    let mut p = vec![true; 144];
                    p[143] = false;
                    p
                }[..]
            )
        );
        // A single image is not corrected (a gap in the texture looks the same).
        let one = movie(data[4 * 144..5 * 144].to_vec(), 1, None);
        assert!(!detect_dead_sensels(&one, &DeadSenselConfig::default()).is_empty());
        let (same, none) = correct_dead_sensels(one.clone(), &DeadSenselConfig::default()).unwrap();
        assert!(none.is_empty());
        assert_eq!(same.data(), one.data());
    }

    /// A 12 x 12 movie of `frames` frames, loaded everywhere in frames `loaded`, with (0, 6) silent.
    fn border_movie(frames: usize, loaded: std::ops::Range<usize>) -> Recording {
        let mut data = Vec::new();
        for f in 0..frames {
            data.extend((0..144).map(|_| if loaded.contains(&f) { 5.0 } else { 0.0 }));
        }
        kill(&mut data, 0, 6);
        movie(data, frames, None)
    }

    #[test]
    fn an_edge_sensel_needs_every_neighbour_loaded_in_twice_the_frames() {
        // On the border row, its five neighbours loaded in 3 frames: an interior sensel would be dead,
        // an edge sensel is not (the load may end just beyond it).
        let config = DeadSenselConfig::default();
        assert!(detect_dead_sensels(&border_movie(10, 2..5), &config).is_empty());
        // In 6 frames it is.
        let dead = detect_dead_sensels(&border_movie(10, 2..8), &config);
        assert_eq!(
            dead,
            [DeadSensel {
                row: 0,
                col: 6,
                surrounded_frames: 6
            }]
        );
        // A corner (two sides) never is.
        let mut data: Vec<f64> = vec![5.0; 10 * 144];
        kill(&mut data, 0, 0);
        assert!(detect_dead_sensels(&movie(data, 10, None), &config).is_empty());
    }
}
