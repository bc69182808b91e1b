// Self-calibration of the cameras' intrinsics in the bundle adjustment: which entries are refined, the
// prior on them (the given intrinsics, intrinsics_sigma), and whether the data can constrain them.
//
// Observability: an entry's posterior standard deviation is the square root of its marginal covariance
// in the whole bundle adjustment (IntrinsicsCovariance: the inverse of J^T J / sigma_px^2 plus the prior
// diag(1 / sigma^2), every pose and the other intrinsics marginalised) at the poses solved with the given
// intrinsics. An entry whose posterior is not below observability_ratio x its prior sigma is held at its
// prior (the data cannot constrain it: markers only near the centre, few views, no depth range) and
// reported with the figures; per camera the worst entry is held first and the test repeated on the rest.
#pragma once

#include <string>
#include <vector>

#include "core/camera.h"
#include "mapper/bundle.h"
#include "mapper/mapper.h"

namespace mcmt {

// The entries `refine` asks for, in IntrinsicsVector's layout (rational radtan k4..k6: never).
std::vector<int> RequestedIntrinsics(IntrinsicsRefinement refine, const CameraModel& model);
std::vector<double> PriorSigma(const IntrinsicsSigma& sigma, const CameraModel& model);

// Fraction of an 8 x 6 grid of image cells holding corners of camera c's active observations; views:
// frames it saw markers in.
double ImageCoverage(const BundleProblem& problem, int camera, int* views);

// Sets problem->intrinsics for every camera refined (the reference camera too: its pose is the rig
// frame, its intrinsics are unknowns like the others'), holding the entries the data cannot constrain.
// sigma_px: the corner noise the information is scaled by (the RMS of the solve before).
std::vector<IntrinsicsReport> PlanIntrinsicsRefinement(const IntrinsicsSettings& settings,
                                                       const std::vector<std::string>& camera_names,
                                                       double sigma_px, BundleProblem* problem);

// After a solve with the intrinsics free: changes from the given values that the data do not call for
// are undone and the entries held at the given values (a calibration the data agree with is not traded
// for the data's own noise). Per camera, first all its entries together: held when the changes'
// Mahalanobis distance is within the chi-square level of a 5 % chance, family-wise over the cameras, of
// changing a right calibration; a camera that differs keeps free only its entries changed by more than
// 1.96 posterior sigmas, tested one at a time given those held before. Returns true when an entry was
// held (the caller re-solves). `information` (optional): the information the test used (at the
// parameters before any entry was held).
bool KeepAgreeingIntrinsics(double sigma_px, std::vector<IntrinsicsReport>* reports, BundleProblem* problem,
                            IntrinsicsInformation* information = nullptr);

// After the solve: the refined values and posterior sigmas into the reports. The covariance from
// `information` (KeepAgreeingIntrinsics', the entries held since dropped) when given, else from the
// information at the current parameters.
void FinishIntrinsicsReports(BundleProblem* problem, double sigma_px, std::vector<IntrinsicsReport>* reports,
                             const IntrinsicsInformation* information = nullptr);

// report.json's "intrinsics" member (one line per camera considered; empty when none), each line
// ending ",\n": given and refined values, prior and posterior sigmas, which entries were held and why.
std::string SelfCalibrationJson(const MapReport& report);

}  // namespace mcmt
