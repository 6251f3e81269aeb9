"""The oracle detector (explore_seg.core.detector.oracle), through Detector."""

from __future__ import annotations

import numpy as np
import pytest

from detector_support import SIM_IDS
from explore_seg.core.detector import Detector, DetectorParams



def _semantic() -> np.ndarray:
    sem = np.ones((60, 80), np.uint8)
    sem[10:20, 5:15] = 3     # chair A: 10x10
    sem[30:50, 40:70] = 4    # table
    sem[40:55, 10:20] = 3    # chair B
    sem[0:3, 70:73] = 3      # 9 px: under oracle_min_area_px
    sem[25:35, 20:30] = 5    # lamp: not mapped
    return sem


def _rgb(sem: np.ndarray) -> np.ndarray:
    return np.zeros(sem.shape + (3,), np.uint8)


def test_oracle_boxes_from_semantic_image():
    det = Detector(DetectorParams(backend="oracle"), sim_class_ids=SIM_IDS)
    sem = _semantic()
    got = [(d.cls_name, d.class_id, d.score, d.box_xyxy) for d in det.detect(_rgb(sem),
                                                                             semantic=sem)]
    assert got == [("chair", 56, 0.9, (5.0, 10.0, 15.0, 20.0)),
                   ("chair", 56, 0.9, (10.0, 40.0, 20.0, 55.0)),
                   ("dining table", 60, 0.9, (40.0, 30.0, 70.0, 50.0))]
    assert det.backend_name == "oracle" and det.network is None


def test_oracle_splits_touching_objects_by_instance():
    det = Detector(DetectorParams(backend="oracle", oracle_min_area_px=1),
                   sim_class_ids=SIM_IDS)
    sem = np.zeros((20, 30), np.int32)
    sem[5:15, 2:22] = 3
    inst = np.zeros_like(sem)
    inst[5:15, 2:12], inst[5:15, 12:22] = 7, 8
    merged = det.detect(_rgb(sem), semantic=sem)
    split = det.detect(_rgb(sem), semantic=sem, instance=inst)
    assert [d.box_xyxy for d in merged] == [(2.0, 5.0, 22.0, 15.0)]
    assert [d.box_xyxy for d in split] == [(2.0, 5.0, 12.0, 15.0), (12.0, 5.0, 22.0, 15.0)]


def test_oracle_miss_probability_one_reports_nothing():
    det = Detector(DetectorParams(backend="oracle", oracle_miss_prob=1.0),
                   sim_class_ids=SIM_IDS)
    sem = _semantic()
    assert det.detect(_rgb(sem), semantic=sem) == []


def test_oracle_class_filter_and_score():
    det = Detector(DetectorParams(backend="oracle", classes=("dining table",),
                                  oracle_score=0.6), sim_class_ids=SIM_IDS)
    sem = _semantic()
    assert [(d.cls_name, d.score) for d in det.detect(_rgb(sem), semantic=sem)] == [
        ("dining table", 0.6)]


@pytest.mark.parametrize("seed", [0, 1])
def test_oracle_jitter_is_seeded_bounded_and_clipped(seed):
    params = DetectorParams(backend="oracle", oracle_jitter_px=2.0, oracle_seed=seed)
    sem = _semantic()
    a = Detector(params, sim_class_ids=SIM_IDS).detect(_rgb(sem), semantic=sem)
    b = Detector(params, sim_class_ids=SIM_IDS).detect(_rgb(sem), semantic=sem)
    exact = Detector(DetectorParams(backend="oracle"),
                     sim_class_ids=SIM_IDS).detect(_rgb(sem), semantic=sem)
    assert a == b and len(a) == len(exact)
    shift = np.abs(np.array([d.box_xyxy for d in a]) - [d.box_xyxy for d in exact])
    assert shift.max() > 0 and shift.max() < 2.0 * 6  # 6 sigma
    assert all(0 <= d.box_xyxy[0] < d.box_xyxy[2] <= 80 and
               0 <= d.box_xyxy[1] < d.box_xyxy[3] <= 60 for d in a)
