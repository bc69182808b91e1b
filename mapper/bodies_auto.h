// `objects: auto` and an object with `ids: auto`: the mapper groups the ids no object claims into rigid
// bodies itself, before mapping them as if they had been declared (mapper/bodies.h).
//
//   rigid pair   two markers seen together (one camera, one frame) in at least min_marker_support frames,
//                whose relative pose agrees with its medoid (the marker graph's consistency thresholds)
//                in at least kRigidFraction of them. Bodies are the connected groups of rigid pairs.
//   static       a marker whose pose in every camera that sees it (in at least min_marker_support
//                frames) agrees with that camera's medoid pose in at least kStaticFraction of its
//                frames: a body is static when all its markers are.
//   foreign      an id that joins no body it could be mapped with: in no rigid pair and seen in fewer
//                than max(10, min_marker_support) camera frames, or static in one camera's view only (a real
//                marker seen by one camera constrains nothing, and a false detection stuck in the image
//                looks the same).
// Found bodies are named static_1, static_2, ... and body_1, body_2, ... by decreasing observations; an
// object with `ids: auto` takes the largest found body of its kind (static or not) and its name.
#pragma once

#include <string>
#include <vector>

#include "mapper/bodies.h"
#include "mapper/mapper.h"
#include "mapper/stages.h"

namespace mcmt {

constexpr double kRigidFraction = 0.8;
constexpr double kStaticFraction = 0.9;

// Do the bodies carry an `ids: auto` object (or `objects: auto`)?
bool HasAutoBodies(const std::vector<MapperBody>& bodies);

// Groups the ids seen that no declared body claims by explicit ids into bodies, and names them (an
// `ids: auto` body of `declared` takes the largest found body of its kind, in the order declared; the
// others get names no declared body has). Marker sizes: the first auto body's.
AutoBodies GroupIntoBodies(const std::vector<StoredMessage>& messages,
                           const std::vector<MapperBody>& declared, const BodiesInputs& inputs,
                           const MapperOptions& options, int threads);

// The bodies to map: the declared ones with explicit ids (an `other` object keeps the ids the grouping
// did not use), then every found body; an `ids: auto` object replaced by the body it takes (or, when
// none is of its kind, named in *report's warnings and left out). Found bodies take the sizes of the
// first auto object.
std::vector<MapperBody> ResolveAutoBodies(const std::vector<MapperBody>& declared, const AutoBodies& found,
                                          MapReport* report);

// A ready `objects:` section for the rig file: every body to map (explicit ids; `other` kept), with
// `rig_frame` when given, else a comment suggesting the largest static body. objects.yaml holds it.
std::string ObjectsSectionYaml(const std::vector<MapperBody>& bodies, const std::string& rig_frame);

// report.json's "auto_objects": the bodies found (name, static, ids, observations, cameras), the foreign
// ids with why, and the objects: section; empty when auto did not run.
std::string AutoBodiesJson(const AutoBodies& found);

}  // namespace mcmt
