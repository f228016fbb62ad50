#pragma once
// DICOM series: a folder of single-frame slices of one series (CT, MR, PET
// as scanners and PACS export them), read with GDCM (Debian libgdcm-dev),
// which also decodes compressed transfer syntaxes (JPEG, JPEG 2000, RLE).
//
// Every file of the folder (not its sub-folders; hidden files and DICOMDIR
// skipped; a FIFO or device refused by name, as every input) must be a
// slice of the same series: same SeriesInstanceUID, Rows x Columns,
// ImageOrientationPatient, PixelSpacing
// and pixel format (one sample of 8, 16 or signed 32 bits), else the folder
// is refused naming the two files that differ. Slices are ordered by their
// ImagePositionPatient projected on the slice normal (row cosine x column
// cosine), not by file name or InstanceNumber; the gaps between positions
// must be equal (within 0.1 %), two slices at one position are refused, as
// a position past float32's range. Each slice's uncompressed PixelData must
// hold its whole plane (GDCM zero-fills a short one).
// Grid: x along the rows (spacing = PixelSpacing's column spacing, its
// second value), y down the columns, z along the normal at the position
// step; origin = the first slice's ImagePositionPatient. The direction
// cosines themselves are not applied (as VTK's vtkDICOMImageReader): the
// grid lives in the series' own axes. RescaleSlope / RescaleIntercept are
// applied per slice as NIfTI's scaling is (float32 samples) whenever a slice
// is not 1 / 0; otherwise the stored type is kept.
#include <memory>
#include <string>

#include "keymesh/mesh/plane_source.hpp"
#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::io {

// The series' header is read from every file (not their pixels); planes
// are then read one file each, so --memory-limit streams a series.
std::unique_ptr<PlaneSource> open_dicom_series(const std::string& folder);

}  // namespace keymesh::io
