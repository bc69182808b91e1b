// mcmt's definitions of four OpenCV functions in OpenCV's place (opencv_overrides.cc): the same results
// bit for bit, cheaper, for the calls cv::aruco::detectMarkers makes.
#pragma once

namespace mcmt {

// Does nothing. MarkerDetector calls it so that every program that detects markers links
// opencv_overrides.cc from the mcmt_detector archive: nothing else names that file's symbols, and the
// linker takes an archive member only for a symbol something references.
void LinkOpenCvOverrides();

}  // namespace mcmt
