//! An input that a stop can end: the source is read on a thread of its own, so that a signal ends the
//! input at once instead of waiting for a read that may never return (stdin); the reader then sees the
//! end of the input, and a stream session writes its `end` line.

use std::io::Read;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};

/// What the reader thread hands on.
enum Chunk {
    Data(Vec<u8>),
    /// The end of the input, or a stop: read as the end of the input.
    End,
}

/// The reading end: a [`Read`] that ends at the source's end or at a stop, whichever comes first.
pub struct StoppableInput {
    chunks: Receiver<Chunk>,
    current: Vec<u8>,
    at: usize,
    ended: bool,
}

/// Ends a [`StoppableInput`] early (from a signal handler's thread, say).
#[derive(Clone, Debug)]
pub struct InputStop(SyncSender<Chunk>);

impl InputStop {
    /// The input ends after what was already read.
    pub fn stop(&self) {
        let _ = self.0.send(Chunk::End);
    }
}

impl std::fmt::Debug for StoppableInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StoppableInput")
            .field("ended", &self.ended)
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for Chunk {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Data(data) => write!(f, "Data({} bytes)", data.len()),
            Self::End => f.write_str("End"),
        }
    }
}

impl StoppableInput {
    /// Starts the reader thread on the source `open` gives there (`|| std::io::stdin().lock()`); a
    /// read error ends the input like its end.
    pub fn start<R: Read>(open: impl FnOnce() -> R + Send + 'static) -> (Self, InputStop) {
        let (sender, chunks) = sync_channel(16);
        let feed = sender.clone();
        std::thread::spawn(move || {
            let mut source = open();
            loop {
                let mut buf = vec![0u8; 64 * 1024];
                match source.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        buf.truncate(n);
                        if feed.send(Chunk::Data(buf)).is_err() {
                            return;
                        }
                    }
                }
            }
            let _ = feed.send(Chunk::End);
        });
        let input = Self {
            chunks,
            current: Vec::new(),
            at: 0,
            ended: false,
        };
        (input, InputStop(sender))
    }
}

impl Read for StoppableInput {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        while self.at == self.current.len() {
            if self.ended {
                return Ok(0);
            }
            match self.chunks.recv() {
                Ok(Chunk::Data(data)) => (self.current, self.at) = (data, 0),
                Ok(Chunk::End) | Err(_) => self.ended = true,
            }
        }
        let n = buf.len().min(self.current.len() - self.at);
        buf[..n].copy_from_slice(&self.current[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn the_input_is_read_whole_or_up_to_a_stop() {
        let data: Vec<u8> = (0..200_000u32).map(|i| i as u8).collect();
        let source = data.clone();
        let (mut input, _stop) = StoppableInput::start(move || std::io::Cursor::new(source));
        let mut read = Vec::new();
        input.read_to_end(&mut read).unwrap();
        assert_eq!(read, data);

        // A source that stalls after its first bytes (stdin with nothing typed): the stop ends the
        // input.
        let (_never, stalled) = std::sync::mpsc::channel::<()>();
        let source = std::io::Cursor::new(vec![7u8; 10]).chain(Stalled(stalled));
        let (mut input, stop) = StoppableInput::start(move || source);
        let mut first = [0u8; 10];
        input.read_exact(&mut first).unwrap();
        stop.stop();
        let mut rest = Vec::new();
        input.read_to_end(&mut rest).unwrap();
        assert_eq!((first, rest.len()), ([7u8; 10], 0));
    }

    /// A source whose read never returns while its sender lives.
    struct Stalled(std::sync::mpsc::Receiver<()>);

    impl Read for Stalled {
        fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
            let _ = self.0.recv();
            Ok(0)
        }
    }
}
