// The detector's AVX2 code: the side model's evaluation (detector/side_model_lanes.inc, four bins at a
// time) and the candidate search's threshold, contour scan and warp (detector/opencv_overrides.cc) run AVX2
// code where the CPU has AVX2 and their SSE2 code elsewhere, chosen once at run time for all of them. Both
// give the same values to the bit, so the corners do not depend on the machine (SideModel.Avx2IsSse2,
// CandidateSearch.Avx2ThresholdIsSse2, CandidateSearch.Avx2WarpIsSse2,
// CandidateSearch.FindContoursIsOpenCVs). MCMT_NO_AVX2 set (and not "0") in the environment when the choice
// is first made: the SSE2 code everywhere.
#pragma once

namespace mcmt {

bool DetectorAvx2Available();  // the CPU has AVX2 (and this build the AVX2 code: GCC on x86-64)
bool DetectorUsesAvx2();       // the AVX2 code runs
// Test hook: the AVX2 code (where available) or the SSE2 code from now on; returns DetectorUsesAvx2()
// before.
bool UseDetectorAvx2(bool use);

}  // namespace mcmt
