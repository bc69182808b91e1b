// The mapper on the simulator's sessions: the one way the mapper's tests, the report's tests and the mapper
// benchmark make synthetic detections (sim::SimulateSession, sim/session.cc) and the mapper's options for
// them. Errors against the truth: sim::Evaluate (sim/eval.h).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mapper/mapper.h"
#include "mcmt/detections_t.hpp"
#include "sim/sim.h"

namespace mcmt {
namespace test {

// The mapper tests' session: sim's defaults (5 cameras on a 1 m circle, 640x480, 60 deg; the four_sided
// object, 4 cm markers) with `frames` frames at 30 fps, every camera's intrinsics a little different
// (intrinsics_spread 0.02), corner noise `noise_px`; `seed` seeds the rig's spread, the trajectory and the
// detections.
sim::SessionOptions MapperSession(int frames, uint64_t seed = 1, double noise_px = 0.1);

// A marker of side `size` fixed in the room (not on the object), facing up and a little sideways below the
// object's motion, as a static body with the frames of `like`.
sim::SceneBody RoomMarker(int id, double size, const std::vector<sim::SimFrame>& like);

// The mapper's options for a simulated truth: its cameras (or only `cameras`), its marker sizes and
// dictionary, other options at their defaults.
MapperOptions MapperOptionsFor(const sim::GroundTruth& truth, const std::vector<std::string>& cameras = {});

// The mapper on `messages` in their order.
MapResult MapMessages(const std::vector<detections_t>& messages, const MapperOptions& options);

// The messages `keep` is true for, in their order.
std::vector<detections_t> Filter(const std::vector<detections_t>& messages,
                                 const std::function<bool(const detections_t&)>& keep);

}  // namespace test
}  // namespace mcmt
