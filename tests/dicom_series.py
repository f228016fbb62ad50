"""A DICOM series written slice by slice with pydicom (python3-pydicom) from
a known numpy volume: the independent reference of the DICOM reader's tests
(tests/cli/test_formats_cli.py, tests/python/test_formats.py)."""
import os
import random

import numpy as np


def write_dicom_series(folder, volume_zyx, pixel_spacing=(0.7, 0.9), step=2.5, origin=(-20.0, 10.0, 5.0),
                       orientation=(1, 0, 0, 0, 1, 0), slope=2.0, intercept=-100.0, series="1.2.826.0.1.3680043.2.1125.1",
                       shuffle=True, names=None):
    """One file per slice, in shuffled order under random names, so that only
    ImagePositionPatient can order them. pixel_spacing = (row spacing = y,
    column spacing = x), as DICOM orders PixelSpacing."""
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian
    os.makedirs(folder, exist_ok=True)
    r, c = np.array(orientation[:3], float), np.array(orientation[3:], float)
    normal = np.cross(r, c)
    order = list(range(volume_zyx.shape[0]))
    if shuffle:
        random.Random(7).shuffle(order)
    for n, k in enumerate(order):
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2"  # CT Image Storage
        meta.MediaStorageSOPInstanceUID = f"{series}.{k + 1}"
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        ds = Dataset()
        ds.file_meta = meta
        ds.is_little_endian, ds.is_implicit_VR = True, False
        ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, meta.MediaStorageSOPInstanceUID
        ds.Modality, ds.PatientName, ds.StudyInstanceUID = "CT", "Test^Keymesh", series + ".0"
        ds.SeriesInstanceUID, ds.InstanceNumber = series, k + 1
        ds.ImagePositionPatient = [f"{v:.10g}" for v in np.array(origin) + k * step * normal]
        ds.ImageOrientationPatient = [f"{v:.10g}" for v in orientation]
        ds.PixelSpacing = [f"{v:.10g}" for v in pixel_spacing]
        ds.SliceThickness = f"{step:.10g}"
        ds.Rows, ds.Columns = volume_zyx.shape[1], volume_zyx.shape[2]
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
        ds.RescaleSlope, ds.RescaleIntercept = f"{slope:g}", f"{intercept:g}"
        ds.PixelData = np.ascontiguousarray(volume_zyx[k].astype("<i2")).tobytes()
        name = names[n] if names else f"IM{random.Random(k).randrange(10**6):06d}_{n}"
        ds.save_as(os.path.join(folder, name), write_like_original=False)
