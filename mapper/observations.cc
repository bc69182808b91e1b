// Stages: frames, observations, square hypotheses (step 1).
#include <algorithm>
#include <numeric>
#include <sstream>

#include "mapper/parallel.h"
#include "mapper/stages.h"

namespace mcmt {

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

std::string JoinNames(const std::vector<std::string>& names, size_t max) {
  std::string out;
  for (size_t i = 0; i < names.size() && i < max; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > max) out += ", ...";
  return out;
}

std::vector<Frame> AssembleFrames(const std::vector<StoredMessage>& messages, int num_cameras,
                                  int64_t tolerance_us) {
  std::vector<int> order(messages.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    return std::make_pair(messages[x].utime, messages[x].camera) <
           std::make_pair(messages[y].utime, messages[y].camera);
  });
  std::vector<Frame> frames;
  std::vector<int64_t> camera_in_frame(num_cameras, -1);
  for (int i : order) {
    const StoredMessage& m = messages[i];
    const bool join = !frames.empty() && m.utime - frames.back().utime <= tolerance_us &&
                      camera_in_frame[m.camera] != static_cast<int64_t>(frames.size()) - 1;
    if (!join) {
      frames.emplace_back();
      frames.back().utime = m.utime;
      frames.back().seq = m.seq;
    }
    frames.back().messages.push_back(i);
    camera_in_frame[m.camera] = static_cast<int64_t>(frames.size()) - 1;
  }
  return frames;
}

namespace {

// Views: contiguous ranges of observations with the same (frame, camera).
std::vector<std::pair<int, int>> ViewRanges(const std::vector<Observation>& obs) {
  std::vector<std::pair<int, int>> views;
  for (size_t i = 0; i < obs.size();) {
    size_t j = i;
    while (j < obs.size() && obs[j].view == obs[i].view) ++j;
    views.emplace_back(static_cast<int>(i), static_cast<int>(j));
    i = j;
  }
  return views;
}

// The observations of one message: ids outside the whitelist are counted, ids seen twice dropped.
bool AddMessage(const StoredMessage& m, int frame, int view, const std::vector<std::string>& camera_names,
                const MapperOptions& options, const MarkerConfig& whitelist, Observations* out,
                MapReport* report) {
  std::map<int, int> count;
  for (const StoredMarker& mk : m.markers) ++count[mk.id];
  bool any = false;
  for (const StoredMarker& mk : m.markers) {
    if (!whitelist.Accepts(mk.id)) {
      ++report->ignored_ids;
      continue;
    }
    const int c = count[mk.id];
    if (c != 1) {  // the same id twice in one camera frame: which one is the marker is unknown
      ++report->duplicates;
      if (c > 1) {
        if (report->duplicate_examples.size() < 20)
          report->duplicate_examples.push_back("camera " + camera_names[m.camera] + " seq " +
                                               std::to_string(m.seq) + " id " + std::to_string(mk.id) + " x" +
                                               std::to_string(c));
        count[mk.id] = -c;
      }
      continue;
    }
    auto it = out->marker_index.find(mk.id);
    if (it == out->marker_index.end()) {
      it = out->marker_index.emplace(mk.id, out->NumMarkers()).first;
      out->marker_ids.push_back(mk.id);
    }
    Observation ob;
    ob.frame = frame;
    ob.camera = m.camera;
    ob.marker = it->second;
    ob.view = view;
    ob.utime = m.utime;
    ob.corners = mk.corners;
    ob.side = options.sizes.Get(mk.id);
    out->obs.push_back(ob);
    any = true;
  }
  return any;
}

}  // namespace

Observations CollectObservations(const std::vector<StoredMessage>& messages, const std::vector<Frame>& frames,
                                 const std::vector<std::string>& camera_names, const MapperOptions& options,
                                 MapReport* report) {
  MarkerConfig whitelist;
  whitelist.ids = options.marker_ids;
  Observations out;
  out.camera_messages.assign(camera_names.size(), 0);
  // Reserved for every whitelisted detection (the duplicates, rarely any, are the slack): grown by
  // doubling, the 448-byte observations took up to 2x their size from here to the end of the bundle
  // adjustment, the mapper's peak (8-camera board, 3000 frames: 58.7 MB for 92800 observations instead of
  // 41.6).
  size_t accepted = 0;
  for (const Frame& frame : frames)
    for (int mi : frame.messages)
      for (const StoredMarker& mk : messages[mi].markers) accepted += whitelist.Accepts(mk.id);
  out.obs.reserve(accepted);
  int view_count = 0;
  for (size_t f = 0; f < frames.size(); ++f) {
    for (int mi : frames[f].messages) {
      const StoredMessage& m = messages[mi];
      ++out.camera_messages[m.camera];
      if (AddMessage(m, static_cast<int>(f), view_count, camera_names, options, whitelist, &out, report))
        ++view_count;
    }
  }
  report->observations_total = static_cast<int>(out.obs.size());
  if (out.obs.empty())
    throw MapperError("no marker observations" +
                      std::string(options.marker_ids.empty() ? "" : " of markers.ids") + " in " +
                      std::to_string(messages.size()) + " detections messages");
  out.views = ViewRanges(out.obs);
  return out;
}

void EstimateHypotheses(const std::vector<CameraModel>& models, double tau_e, int threads,
                        Observations* observations) {
  std::vector<Observation>& obs = observations->obs;
  std::vector<SquarePose>& poses = observations->poses;
  poses.assign(obs.size(), SquarePose());
  ParallelFor(static_cast<int>(obs.size()), threads, [&](int i) {
    Observation& ob = obs[i];
    if (!(ob.side > 0)) return;
    poses[i] = EstimateSquarePose(models[ob.camera], ob.corners, ob.side);
    ob.kept = NumKeptHypotheses(poses[i], tau_e);
  });
}

}  // namespace mcmt
