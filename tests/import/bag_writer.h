// Writes small ROS 1 bags (format 2.0) for the import tests: one chunk (none, bz2 or lz4) holding the
// connections and messages, the connection records repeated after it as rosbag does.
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "import/rosbag.h"

namespace mcmt::import_test {

class Bytes {
 public:
  Bytes& U32(uint32_t v) { return Raw(&v, 4); }
  Bytes& I32(int32_t v) { return Raw(&v, 4); }
  Bytes& F64(double v) { return Raw(&v, 8); }
  Bytes& Str(const std::string& s) {
    U32(static_cast<uint32_t>(s.size()));
    data_ += s;
    return *this;
  }
  Bytes& Raw(const void* p, size_t n) {
    data_.append(static_cast<const char*>(p), n);
    return *this;
  }
  const std::string& str() const { return data_; }

 private:
  std::string data_;
};

inline std::string Field(const std::string& name, const std::string& value) {
  Bytes b;
  b.Str(name + "=" + value);
  return b.str();
}

inline std::string U32Bytes(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }

inline std::string Record(const std::string& header, const std::string& data) {
  Bytes b;
  b.Str(header).Str(data);
  return b.str();
}

struct TestConnection {
  std::string topic, type, definition;
};
struct TestMessage {
  uint32_t connection;
  uint32_t secs, nsecs;
  std::string data;
};

inline std::string ConnectionRecord(uint32_t id, const TestConnection& c) {
  const std::string header =
      Field("op", std::string(1, '\x07')) + Field("conn", U32Bytes(id)) + Field("topic", c.topic);
  const std::string data = Field("topic", c.topic) + Field("type", c.type) + Field("md5sum", "0") +
                           Field("message_definition", c.definition);
  return Record(header, data);
}

inline void WriteBag(const std::string& path, const std::vector<TestConnection>& connections,
                     const std::vector<TestMessage>& messages, const std::string& compression) {
  std::string chunk;
  for (size_t i = 0; i < connections.size(); ++i) chunk += ConnectionRecord(uint32_t(i), connections[i]);
  for (const TestMessage& m : messages) {
    const std::string time = U32Bytes(m.secs) + U32Bytes(m.nsecs);
    chunk += Record(
        Field("op", std::string(1, '\x02')) + Field("conn", U32Bytes(m.connection)) + Field("time", time),
        m.data);
  }
  std::string packed = chunk;
  if (compression == "bz2") packed = Bz2Compress(chunk);
  if (compression == "lz4") packed = Lz4FrameCompress(chunk);
  std::string out = "#ROSBAG V2.0\n";
  out += Record(Field("op", std::string(1, '\x03')) +
                    Field("conn_count", U32Bytes(uint32_t(connections.size()))) +
                    Field("chunk_count", U32Bytes(1)),
                std::string(64, ' '));
  out += Record(Field("op", std::string(1, '\x05')) + Field("compression", compression) +
                    Field("size", U32Bytes(uint32_t(chunk.size()))),
                packed);
  for (size_t i = 0; i < connections.size(); ++i) out += ConnectionRecord(uint32_t(i), connections[i]);
  std::ofstream(path, std::ios::binary) << out;
}

// apriltag_msgs/ApriltagArrayStamped as the TagSLAM bags define it.
inline const char* AprilTagDefinition() {
  return "# ApriltagArrayStamped\nstd_msgs/Header header\nApriltag[] apriltags\n"
         "================================================================================\n"
         "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"
         "================================================================================\n"
         "MSG: apriltag_msgs/Apriltag\n# constants and comments are skipped\nint32 SOME_CONSTANT=3\n"
         "int32 id                       # Id of the apriltag\nstring family\nint32 hamming\nint32 border\n"
         "int32 bits\ngeometry_msgs/Point center\ngeometry_msgs/Point[4] corners\n"
         "================================================================================\n"
         "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n";
}

struct TestTag {
  int id;
  double corners[4][2];  // in the message's (AprilTag) order
};

inline std::string AprilTagArray(uint32_t seq, uint32_t secs, uint32_t nsecs,
                                 const std::vector<TestTag>& tags) {
  Bytes b;
  b.U32(seq).U32(secs).U32(nsecs).Str("cam");
  b.U32(static_cast<uint32_t>(tags.size()));
  for (const TestTag& t : tags) {
    b.I32(t.id).Str("tf36h11").I32(0).I32(1).I32(6);
    b.F64(0).F64(0).F64(0);
    for (const auto& c : t.corners) b.F64(c[0]).F64(c[1]).F64(0.0);
  }
  return b.str();
}

}  // namespace mcmt::import_test
