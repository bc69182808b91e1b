// Detections-only sessions in memory: the rig, the bodies and every camera's detections, for tests and
// benchmarks; a rig file and a log written from them.
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_writer.h"
#include "sim/sim.h"
#include "sim/sim_internal.h"

namespace fs = std::filesystem;

namespace mcmt {
namespace sim {

GroundTruth Session::Truth(size_t body) const {
  const SceneBody& b = bodies.at(body);
  GroundTruth truth;
  truth.object = b.object.name;
  truth.dictionary = dictionary;
  truth.marker_size = b.object.Sizes().default_size;
  for (const SimMarker& m : b.object.markers) truth.marker_sizes[m.id] = m.size;
  truth.fps = fps;
  truth.cameras = cameras;
  truth.markers = b.object.markers;
  truth.frames = b.frames;
  return truth;
}

std::vector<detections_t> Session::Messages() const {
  std::vector<detections_t> out;
  for (const auto& frame : views) out.insert(out.end(), frame.begin(), frame.end());
  return out;
}

Session SimulateSession(const SessionOptions& o) {
  SceneBody body;
  body.object = MakeObject(o.object);
  body.name = body.object.name;
  body.frames = MakeTrajectory(o.trajectory);
  std::vector<SceneBody> bodies = {body};
  bodies.insert(bodies.end(), o.extra_bodies.begin(), o.extra_bodies.end());
  Session s = SimulateSession(MakeRig(o.rig), bodies, o.detections, o.trajectory.seed, o.camera_stagger_us);
  s.fps = o.trajectory.fps;
  return s;
}

Session SimulateSession(const std::vector<SimCamera>& cameras, const std::vector<SceneBody>& bodies,
                        const DetectionSimOptions& options, uint64_t seed, int64_t camera_stagger_us) {
  if (bodies.empty()) throw std::invalid_argument("SimulateSession: no body");
  const std::vector<SimFrame>& frames = bodies[0].frames;
  for (const SceneBody& b : bodies)
    if (b.frames.size() != frames.size())
      throw std::invalid_argument("SimulateSession: body '" + b.name + "' has " +
                                  std::to_string(b.frames.size()) + " frames, '" + bodies[0].name + "' " +
                                  std::to_string(frames.size()));
  Session s;
  s.cameras = cameras;
  s.bodies = bodies;
  s.dictionary = options.dictionary;
  s.views.resize(frames.size());
  SimObject scene;
  size_t current = 0;
  internal::SimulateFrames(
      cameras, frames.size(), options, seed,
      [&](size_t i, SimFrame* frame) -> const SimObject& {
        current = i;
        *frame = frames[i];
        if (bodies.size() == 1) return bodies[0].object;
        scene = SceneAt(bodies, i);  // every body in the rig frame
        frame->rig_from_object = Rigid3::Identity();
        return scene;
      },
      nullptr,
      [&](size_t k, const detections_t& message) {
        s.views[current].push_back(message);
        s.views[current].back().utime += static_cast<int64_t>(k) * camera_stagger_us;
      });
  return s;
}

std::string WriteSessionRig(const std::string& dir, const Session& session, const std::string& extra) {
  const MarkerSizes sizes = session.object().Sizes();
  std::ostringstream s;
  s << "markers:\n  dictionary: " << session.dictionary << "\n  size: " << YamlNumber(sizes.default_size)
    << "\n";
  if (!sizes.overrides.empty()) {
    s << "  sizes: {";
    const char* separator = "";
    for (const auto& [id, size] : sizes.overrides) {
      s << separator << id << ": " << YamlNumber(size);
      separator = ", ";
    }
    s << "}\n";
  }
  s << "cameras:\n";
  for (const SimCamera& c : session.cameras) {
    WriteIntrinsicsOpenCv((fs::path(dir) / (c.name + ".yml")).string(), c.model);
    s << "  - name: " << c.name << "\n    intrinsics: " << c.name << ".yml\n";
  }
  s << extra;
  const std::string path = (fs::path(dir) / "rig.yaml").string();
  WriteFileAtomic(path, s.str());
  return path;
}

int64_t WriteMessagesLog(const std::string& path, const std::vector<detections_t>& messages,
                         const std::function<int64_t(const detections_t&)>& arrival_delay_us) {
  const std::string tmp = path + ".tmp";
  std::error_code ec;
  fs::remove(tmp, ec);
  {
    EventLogWriter log(tmp);
    for (const detections_t& d : messages) {
      const std::vector<uint8_t> bytes = Encode(d);
      log.Write(d.utime + (arrival_delay_us ? arrival_delay_us(d) : 0), DetectionsChannel(d.camera),
                bytes.data(), bytes.size());
    }
    log.Close();
  }
  fs::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "': " + ec.message());
  return static_cast<int64_t>(messages.size());
}

}  // namespace sim
}  // namespace mcmt
