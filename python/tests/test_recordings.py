"""Reading recordings, stance phases and features, checked against numpy."""

import numpy as np
import pytest

import presrs
from conftest import SHARED

WALK = SHARED / "data" / "tekscan" / "FrasP01L.asf"


def test_a_tekscan_walk_reads_with_its_header():
    rec = presrs.read(WALK)
    assert rec.frames.shape == (205, 60, 21)
    assert rec.frames.dtype == np.float64
    assert rec.shape == (60, 21) and len(rec) == 205
    assert rec.units == "KPa" and rec.units_stated
    assert rec.frame_period_s == pytest.approx(1 / 31.25, rel=0.01)
    assert rec.sensor["row_pitch_mm"] == pytest.approx(5.08)
    assert rec.mask.shape == (60, 21) and rec.mask.dtype == bool
    # The total load is the sum over present sensels, as numpy computes it.
    expected = np.where(rec.mask, 0.0, rec.frames).sum(axis=(1, 2))
    np.testing.assert_allclose(rec.total_load(), expected, rtol=1e-12)


def test_the_walk_has_its_complete_stances():
    stances = presrs.segment(presrs.read(WALK))
    complete = [s for s in stances if not s.partial]
    assert len(complete) == 5
    for s in stances:
        assert s.start <= s.sample_frame < s.end == s.start + s.length
        assert s.start <= s.peak_frame < s.end


def test_segment_takes_a_recording_frames_or_totals_alike():
    rec = presrs.read(WALK)
    by_recording = presrs.segment(rec)
    by_frames = presrs.segment(rec.frames)
    by_totals = presrs.segment(rec.total_load())
    as_tuples = lambda stances: [(s.start, s.length, s.partial) for s in stances]
    assert as_tuples(by_recording) == as_tuples(by_frames) == as_tuples(by_totals)


def test_segment_parameters_are_checked_by_name():
    assert "min_stance_frames" in presrs.segment_params()
    rec = presrs.read(WALK)
    long_only = presrs.segment(rec, min_stance_frames=1000)
    assert long_only == []
    with pytest.raises(presrs.DataError, match="unknown parameter"):
        presrs.segment(rec, no_such_parameter=1)
    with pytest.raises(ValueError):
        presrs.segment(rec, on_fraction=-1.0)


def test_npy_written_by_numpy_reads_back_exactly(tmp_path):
    frames = np.random.default_rng(7).random((5, 9, 11)) * 300
    np.save(tmp_path / "movie.npy", frames)
    rec = presrs.read(tmp_path / "movie.npy")
    np.testing.assert_array_equal(rec.frames, frames)
    assert rec.frame_period_s is None and not rec.units_stated


def test_a_recording_from_arrays():
    frames = np.zeros((4, 3, 2), dtype=np.uint8)
    frames[1:3] = 7
    rec = presrs.Recording(frames, frame_period_s=0.01)
    assert rec.frames.shape == (4, 3, 2) and rec.frame_period_s == 0.01
    np.testing.assert_array_equal(rec.total_load(), [0, 42, 42, 0])
    with pytest.raises(presrs.DataError, match="frame_period_s"):
        presrs.Recording(frames, frame_period_s=0)


def test_a_missing_file_is_an_oserror_naming_it(tmp_path):
    missing = tmp_path / "nowhere.asf"
    with pytest.raises(presrs.FileError) as caught:
        presrs.read(missing)
    assert isinstance(caught.value, OSError)
    assert isinstance(caught.value, presrs.PresrsError)
    assert caught.value.errno == 2
    assert "nowhere.asf" in str(caught.value)


def test_a_malformed_file_is_a_value_error_naming_file_and_line(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("1,2,3\n4,five,6\n")
    with pytest.raises(presrs.DataError) as caught:
        presrs.read(bad)
    assert isinstance(caught.value, ValueError)
    assert "bad.csv" in str(caught.value)
    assert "line 2" in str(caught.value)


def test_features_of_one_image_and_of_a_batch_agree(sim_images):
    images = sim_images[0][:4]
    batch = presrs.features(images)
    assert batch.shape[0] == 4
    for image, row in zip(images, batch):
        np.testing.assert_array_equal(presrs.features(image), row)
    glcm = presrs.features(images, family="glcm")
    assert glcm.shape[0] == 4 and glcm.shape[1] < batch.shape[1]
    with pytest.raises(presrs.DataError, match="family"):
        presrs.features(images, family="wavelets")


def test_fft1d_features_are_numpys_rfft_of_the_row_major_vector(sim_images):
    """The paper's eqs. 3-5: the image vectorised row by row, zero-padded to the next power of two,
    |rfft| (what bench/peer.py computes with numpy)."""
    image = sim_images[0][0][:8, :12]
    ours = presrs.features(image, crop="none")
    n = 1 << (image.size - 1).bit_length()
    theirs = np.abs(np.fft.rfft(image.reshape(-1), n=n))
    np.testing.assert_allclose(ours, theirs, rtol=1e-9, atol=1e-9 * theirs.max())


def test_a_time_last_npy_reads_with_its_axes(tmp_path):
    frames = np.random.default_rng(3).random((6, 5, 40))
    np.save(tmp_path / "time-last.npy", frames)
    rec = presrs.read(tmp_path / "time-last.npy", axes="rows,cols,frames")
    assert rec.frames.shape == (40, 6, 5)
    np.testing.assert_array_equal(rec.frames, np.moveaxis(frames, 2, 0))
    with pytest.raises(presrs.DataError, match="axes"):
        presrs.read(tmp_path / "time-last.npy", axes="rows,rows,frames")


def test_the_detectors_modes_from_python():
    rec = presrs.read(WALK)
    assert presrs.segment_params()["baseline"] == "auto"
    assert len(presrs.segment(rec, baseline="drifting")) == 6
    whole = presrs.segment(rec, baseline="contact")
    assert len(whole) == 1 and whole[0].partial and whole[0].length == len(rec)
    with pytest.raises(presrs.DataError, match="sideways"):
        presrs.segment(rec, baseline="sideways")


def test_a_one_contact_movie_is_one_stance():
    movies = sorted((SHARED / "data" / "real" / "jiku-walk").glob("*.npy"))[:5]
    assert movies
    for movie in movies:
        rec = presrs.read(movie)
        stances = presrs.segment(rec)
        assert len(stances) == 1 and stances[0].partial, movie
        images, kept = presrs.stance_images(rec, include_partial=True)
        assert images.shape == (1,) + rec.shape
