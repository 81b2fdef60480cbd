//! The frames of the stance under way, as a whole-stance model needs them: each frame's summary column
//! ([`crate::stance::summary`]) computed as it arrives, kept in a ring of the model's stance length,
//! and laid into the model's sample (channels x length, zero-padded after the frames used) when the
//! stance is decided. Every buffer is allocated once, for the stream's grid: no allocation per frame.
//!
//! The `area` channel counts the sensels above a fraction of the *stance's* highest sensel, which is
//! known only once the frames used are: each frame's loads are kept, and the area is counted when the
//! sample is laid out. The result is the offline summary of the same frames, to the bit
//! ([`crate::stance::summary::summarise`] and this share the per-frame functions).

use crate::error::{CoreError, Result};
use crate::frame::{FrameView, Grid};
use crate::stance::summary::{
    AREA_CHANNEL, SummaryConfig, contact_area, frame_loads, loads_channels,
};

/// A ring of the last `length` frames' summary columns and loads (see the module docs).
#[derive(Clone, Debug)]
pub struct StanceBuffer {
    config: SummaryConfig,
    length: usize,
    grid: Option<Grid>,
    /// Frame `t`'s column at slot `t % length`: `channels` values each.
    columns: Vec<f64>,
    /// Frame `t`'s sensel loads at slot `t % length`: `grid.len()` values each.
    loads: Vec<f64>,
    /// Frame `t`'s highest value at slot `t % length`.
    peaks: Vec<f64>,
    /// The frame each slot holds (`None`: none yet).
    held: Vec<Option<usize>>,
    regions: Vec<f64>,
    column: Vec<f64>,
    /// The sample laid out: channels x length, row-major.
    sample: Vec<f64>,
}

impl StanceBuffer {
    /// A buffer for samples of `length` frames summarised with `config`; its storage comes with the
    /// stream's grid ([`Self::set_grid`]).
    pub fn new(config: SummaryConfig, length: usize) -> Result<Self> {
        if length == 0 {
            return Err(CoreError::Param {
                name: "stance length",
                reason: "a whole-stance model needs a length of at least one frame".into(),
            });
        }
        let channels = config.channels();
        Ok(Self {
            config,
            length,
            grid: None,
            columns: vec![0.0; channels * length],
            loads: Vec::new(),
            peaks: vec![0.0; length],
            held: vec![None; length],
            regions: vec![0.0; config.region_rows * config.region_cols],
            column: vec![0.0; channels],
            sample: vec![0.0; channels * length],
        })
    }

    /// The frames a sample spans (the model's stance length).
    pub fn length(&self) -> usize {
        self.length
    }

    /// The grid of the sample: channels x length.
    pub fn sample_grid(&self) -> Grid {
        Grid::new(self.config.channels(), self.length)
    }

    /// Checks that frames of `grid` can be summarised, and allocates the loads for them.
    pub fn set_grid(&mut self, grid: Grid) -> Result<()> {
        self.config.check(grid)?;
        self.grid = Some(grid);
        self.loads = vec![0.0; grid.len() * self.length];
        self.held.fill(None);
        Ok(())
    }

    /// Keeps frame `t` (of the grid set), in place of frame `t - length`.
    pub fn keep(&mut self, t: usize, frame: &FrameView<'_>) {
        let grid = frame.grid();
        let (slot, size, channels) = (t % self.length, grid.len(), self.column.len());
        let Some(loads) = self.loads.get_mut(slot * size..(slot + 1) * size) else {
            return;
        };
        self.peaks[slot] = frame_loads(frame, loads);
        loads_channels(
            loads,
            grid,
            &self.config,
            &mut self.regions,
            &mut self.column,
        );
        self.columns[slot * channels..(slot + 1) * channels].copy_from_slice(&self.column);
        self.held[slot] = Some(t);
    }

    /// The sample of frames `start .. start + frames` (at most the length; zeros after them), as the
    /// offline summary of those frames laid into the length gives it. An error if a frame is not held
    /// (it was never kept, or a later one took its slot).
    pub fn sample(&mut self, start: usize, frames: usize) -> Result<FrameView<'_>> {
        self.sample_in(start, frames, self.length)
    }

    /// [`Self::sample`] laid into `length` frames (at most the buffer's): a decision point's sample,
    /// of its own length.
    pub fn sample_in(
        &mut self,
        start: usize,
        frames: usize,
        length: usize,
    ) -> Result<FrameView<'_>> {
        let length = length.min(self.length);
        let frames = frames.min(length);
        let channels = self.column.len();
        let size = self.grid.map_or(0, |grid| grid.len());
        let mut peak = 0.0_f64;
        for t in start..start + frames {
            let slot = t % self.length;
            if self.held[slot] != Some(t) {
                return Err(CoreError::NotEnoughData(format!(
                    "frame {t} of the stance from frame {start} is no longer kept (a whole-stance \
                     model keeps its last {} frames)",
                    self.length
                )));
            }
            peak = peak.max(self.peaks[slot]);
        }
        let contact_level = self.config.contact_fraction * peak;
        let sample = &mut self.sample[..channels * length];
        sample.fill(0.0);
        for (i, t) in (start..start + frames).enumerate() {
            let slot = t % self.length;
            let column = &self.columns[slot * channels..(slot + 1) * channels];
            for (channel, &value) in column.iter().enumerate() {
                sample[channel * length + i] = value;
            }
            let loads = &self.loads[slot * size..(slot + 1) * size];
            sample[AREA_CHANNEL * length + i] = contact_area(loads, contact_level);
        }
        FrameView::new(Grid::new(channels, length), sample, None)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::frame::Frame;
    use crate::stance::summary::{pad_to, summarise};

    /// Frames of a rolling, growing load with absent sensels and negative readings.
    fn frames(grid: Grid, count: usize) -> Vec<Frame> {
        (0..count)
            .map(|t| {
                let values = (0..grid.len())
                    .map(|i| ((i * 7 + t * 13) % 17) as f64 * (t as f64 + 1.0) - 3.0)
                    .collect();
                let mut mask = vec![true; grid.len()];
                mask[(t * 5) % grid.len()] = false;
                Frame::with_mask(grid, values, Some(mask)).unwrap()
            })
            .collect()
    }

    /// Kept frame by frame, any stretch of frames gives the offline summary laid into the length, to
    /// the bit: shorter (padded), exactly the length, and after the ring wrapped.
    #[test]
    fn the_sample_is_the_offline_summary_of_the_same_frames() {
        let grid = Grid::new(9, 6);
        let config = SummaryConfig::default();
        let all = frames(grid, 30);
        let mut buffer = StanceBuffer::new(config, 8).unwrap();
        buffer.set_grid(grid).unwrap();
        for (t, frame) in all.iter().enumerate() {
            buffer.keep(t, &frame.view());
            for frames in 1..=8 {
                if frames > t + 1 {
                    break;
                }
                let start = t + 1 - frames;
                let views: Vec<_> = all[start..=t].iter().map(Frame::view).collect();
                let offline = summarise(&views, &config).unwrap();
                let (padded, _) = pad_to(&offline.view(), 8).unwrap();
                let online = buffer.sample(start, frames).unwrap();
                assert_eq!(online.values(), padded.values(), "t {t}, {frames} frames");
            }
        }
        // A decision point's sample, of its own length.
        let views: Vec<_> = all[24..=28].iter().map(Frame::view).collect();
        let (short, _) = pad_to(&summarise(&views, &config).unwrap().view(), 5).unwrap();
        let online = buffer.sample_in(24, 5, 5).unwrap();
        assert_eq!(online.values(), short.values());
        assert_eq!(online.grid(), short.grid());
        let err = buffer.sample(20, 3).unwrap_err().to_string();
        assert!(err.contains("frame 20"), "{err}");
        assert!(StanceBuffer::new(config, 0).is_err());
        assert!(buffer.set_grid(Grid::new(2, 1)).is_err(), "4 x 2 regions");
    }
}
