// ROS 1 bags (format 2.0) read directly, without ROS: records, chunks (uncompressed, bz2, lz4) and
// connections, and the ROS serialisation of any message whose definition the connection header holds.
//
// A bag is "#ROSBAG V2.0\n" then records: int32 header length, header (fields "name=value", each
// preceded by its int32 length), int32 data length, data (all little-endian). Record types (field op):
//   0x03 bag header, 0x05 chunk (compression none|bz2|lz4, size = uncompressed size; its data holds
//   connection and message records), 0x07 connection (conn, topic; data = connection header: topic, type,
//   md5sum, message_definition), 0x02 message data (conn, time), 0x04 index data, 0x06 chunk info.
// lz4 chunks use the LZ4 frame format (ROS's roslz4). A file compressed as a whole with bzip2
// (*.bag.bz2) is decompressed in memory first. The whole bag is held in memory: fine for detection bags
// (megabytes), not for image bags.
//
//   mcmt::RosBag bag = mcmt::RosBag::Open("tags.bag");       // throws BagError naming the file
//   for (const auto& c : bag.connections()) ...               // topic, type, definition
//   for (const mcmt::BagMessage& m : bag.messages()) {
//     mcmt::RosValue v = bag.Decode(m);                        // fields by name, from the definition
//     int64_t sec = v.At("header.stamp.secs").AsInt();
//   }
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mcmt {

class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A decoded ROS message field: a number, a string, a message (named fields) or an array.
struct RosValue {
  enum class Kind { kNumber, kString, kMessage, kArray };
  Kind kind = Kind::kNumber;
  double number = 0.0;
  int64_t integer = 0;  // integer types (and bool, char, byte); time/duration are messages {secs, nsecs}
  bool is_integer = false;
  std::string text;
  std::vector<std::pair<std::string, RosValue>> fields;  // kMessage, in definition order
  std::vector<RosValue> items;                           // kArray

  // Dotted path into nested messages ("header.stamp.secs"); throws BagError naming the missing field.
  const RosValue& At(const std::string& path) const;
  const RosValue* Find(const std::string& name) const;  // direct field, nullptr if absent
  double AsDouble() const;                              // throws BagError unless a number
  int64_t AsInt() const;
};

// One message definition, parsed (constants dropped): fields with their types.
struct RosField {
  std::string name;
  std::string type;     // "float64", "string", "time", "std_msgs/Header", "apriltag_msgs/Apriltag", ...
  int array_size = -1;  // -1: not an array; 0: variable length (uint32 count); N: fixed
};
struct RosMessageType {
  std::string name;  // "pkg/Name"
  std::vector<RosField> fields;
};

// The connection header's message_definition: the top type's fields, then "MSG: pkg/Name" sections for
// every type it uses. Throws BagError naming the type when a field's type is defined nowhere.
class RosSchema {
 public:
  RosSchema(const std::string& type, const std::string& definition);
  const std::string& type() const { return type_; }
  const RosMessageType& Get(const std::string& type) const;  // throws naming the type
  bool Has(const std::string& type) const { return types_.count(type) > 0; }
  // Decodes one serialised message of the top type; throws BagError when the bytes run out or remain.
  RosValue Decode(const uint8_t* data, size_t size) const;

 private:
  std::string Resolve(const std::string& field_type, const std::string& package) const;
  std::string type_;
  std::map<std::string, RosMessageType> types_;
};

struct BagConnection {
  uint32_t id = 0;
  std::string topic;
  std::string type;
  std::string md5sum;
  std::string definition;
};

struct BagMessage {
  uint32_t connection = 0;
  int64_t time_ns = 0;  // record time (receive time), nanoseconds
  std::vector<uint8_t> data;
};

class RosBag {
 public:
  static RosBag Open(const std::string& path);  // reads, decompresses and indexes; throws BagError
  const std::string& path() const { return path_; }
  const std::vector<BagConnection>& connections() const { return connections_; }
  const std::vector<BagMessage>& messages() const { return messages_; }  // in file order
  const BagConnection& Connection(uint32_t id) const;                    // throws naming the id
  const BagConnection* FindTopic(const std::string& topic) const;
  // Decodes with the schema of the message's connection.
  RosValue Decode(const BagMessage& message) const;
  // "/a (pkg/A), /b (pkg/B)": what the bag holds, for error messages.
  std::string TopicList() const;
  // Chunk compressions seen ("none", "bz2", "lz4") with their counts.
  const std::map<std::string, int>& chunk_compressions() const { return compressions_; }

 private:
  void ReadRecords(const uint8_t* data, size_t size, uint64_t base_offset, bool in_chunk);
  std::string path_;
  std::vector<BagConnection> connections_;
  std::map<uint32_t, size_t> connection_index_;
  std::map<uint32_t, std::shared_ptr<RosSchema>> schemas_;
  std::vector<BagMessage> messages_;
  std::map<std::string, int> compressions_;
};

// Decompressors (exposed for tests and for writers of test bags).
std::string Bz2Decompress(const std::string& data, size_t expected_size, const std::string& what);
std::string Lz4FrameDecompress(const std::string& data, size_t expected_size, const std::string& what);
std::string Bz2Compress(const std::string& data);
std::string Lz4FrameCompress(const std::string& data);

}  // namespace mcmt
