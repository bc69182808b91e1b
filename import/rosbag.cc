// ROS 1 bag reader: see rosbag.h for the format.
#include "import/rosbag.h"

#include <bzlib.h>
#include <lz4frame.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace mcmt {
namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr size_t kMagicSize = sizeof(kMagic) - 1;

uint32_t ReadU32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// "name=value" fields of a record header (or a connection header).
std::map<std::string, std::string> ParseHeader(const uint8_t* p, size_t size, const std::string& where) {
  std::map<std::string, std::string> fields;
  size_t i = 0;
  while (i < size) {
    if (size - i < 4) throw BagError(where + ": header field length cut short");
    const uint32_t len = ReadU32(p + i);
    i += 4;
    if (len > size - i)
      throw BagError(where + ": header field of " + std::to_string(len) + " bytes overruns");
    const std::string field(reinterpret_cast<const char*>(p + i), len);
    i += len;
    const size_t eq = field.find('=');
    if (eq == std::string::npos) throw BagError(where + ": header field without '='");
    fields[field.substr(0, eq)] = field.substr(eq + 1);
  }
  return fields;
}

const std::string& Require(const std::map<std::string, std::string>& h, const std::string& key,
                           const std::string& where) {
  auto it = h.find(key);
  if (it == h.end()) throw BagError(where + ": record has no '" + key + "' field");
  return it->second;
}

uint32_t FieldU32(const std::map<std::string, std::string>& h, const std::string& key,
                  const std::string& where) {
  const std::string& v = Require(h, key, where);
  if (v.size() != 4) throw BagError(where + ": field '" + key + "' is not 4 bytes");
  return ReadU32(reinterpret_cast<const uint8_t*>(v.data()));
}

std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw BagError(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A whole file compressed with bzip2 (one stream or several concatenated, as pbzip2 writes).
std::string Bz2StreamDecompress(const std::string& data, const std::string& what) {
  std::string out;
  size_t in_pos = 0;
  std::vector<char> buffer(1 << 16);
  while (in_pos < data.size()) {
    bz_stream s;
    std::memset(&s, 0, sizeof(s));
    if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) throw BagError(what + ": bzip2 init failed");
    s.next_in = const_cast<char*>(data.data() + in_pos);
    s.avail_in = static_cast<unsigned>(data.size() - in_pos);
    int rc = BZ_OK;
    while (rc == BZ_OK) {
      s.next_out = buffer.data();
      s.avail_out = static_cast<unsigned>(buffer.size());
      rc = BZ2_bzDecompress(&s);
      out.append(buffer.data(), buffer.size() - s.avail_out);
      if (rc == BZ_OK && s.avail_in == 0 && s.avail_out != 0) rc = BZ_UNEXPECTED_EOF;
    }
    in_pos = data.size() - s.avail_in;
    BZ2_bzDecompressEnd(&s);
    if (rc == BZ_UNEXPECTED_EOF) throw BagError(what + ": bzip2 data cut short");
    if (rc != BZ_STREAM_END)
      throw BagError(what + ": not valid bzip2 data (code " + std::to_string(rc) + ")");
  }
  return out;
}

std::string ChunkContent(const std::map<std::string, std::string>& h, const std::string& compression,
                         const uint8_t* payload, uint32_t size, const std::string& where) {
  const uint32_t raw_size = FieldU32(h, "size", where);
  const std::string packed(reinterpret_cast<const char*>(payload), size);
  if (compression == "none") return packed;
  if (compression == "bz2") return Bz2Decompress(packed, raw_size, where);
  if (compression == "lz4") return Lz4FrameDecompress(packed, raw_size, where);
  throw BagError(where + ": chunk compression '" + compression + "' unknown (none, bz2, lz4)");
}

BagConnection ParseConnection(uint32_t id, const std::map<std::string, std::string>& h,
                              const uint8_t* payload, uint32_t size, const std::string& where) {
  const auto c = ParseHeader(payload, size, where + " (connection header)");
  BagConnection conn;
  conn.id = id;
  conn.topic = Require(h, "topic", where);
  conn.type = Require(c, "type", where);
  auto md5 = c.find("md5sum");
  if (md5 != c.end()) conn.md5sum = md5->second;
  auto def = c.find("message_definition");
  if (def != c.end()) conn.definition = def->second;
  return conn;
}

}  // namespace

// ---- decompressors ------------------------------------------------------------------------------------

std::string Bz2Decompress(const std::string& data, size_t expected_size, const std::string& what) {
  std::string out(expected_size, '\0');
  unsigned int out_size = static_cast<unsigned int>(expected_size);
  const int rc = BZ2_bzBuffToBuffDecompress(out.data(), &out_size, const_cast<char*>(data.data()),
                                            static_cast<unsigned int>(data.size()), 0, 0);
  if (rc != BZ_OK) throw BagError(what + ": bz2 chunk does not decompress (code " + std::to_string(rc) + ")");
  if (out_size != expected_size)
    throw BagError(what + ": bz2 chunk gives " + std::to_string(out_size) + " bytes, its header says " +
                   std::to_string(expected_size));
  return out;
}

std::string Lz4FrameDecompress(const std::string& data, size_t expected_size, const std::string& what) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
    throw BagError(what + ": lz4 init failed");
  std::string out(expected_size, '\0');
  size_t in_pos = 0, out_pos = 0;
  size_t rc = 1;
  while (in_pos < data.size() && rc != 0) {
    size_t src = data.size() - in_pos, dst = out.size() - out_pos;
    rc = LZ4F_decompress(ctx, out.data() + out_pos, &dst, data.data() + in_pos, &src, nullptr);
    if (LZ4F_isError(rc)) {
      const std::string name = LZ4F_getErrorName(rc);
      LZ4F_freeDecompressionContext(ctx);
      throw BagError(what + ": lz4 chunk does not decompress (" + name + ")");
    }
    in_pos += src;
    out_pos += dst;
    if (src == 0 && dst == 0) break;
  }
  LZ4F_freeDecompressionContext(ctx);
  if (out_pos != expected_size || rc != 0)
    throw BagError(what + ": lz4 chunk gives " + std::to_string(out_pos) + " bytes, its header says " +
                   std::to_string(expected_size));
  return out;
}

std::string Bz2Compress(const std::string& data) {
  std::string out(data.size() + data.size() / 100 + 601, '\0');
  unsigned int out_size = static_cast<unsigned int>(out.size());
  if (BZ2_bzBuffToBuffCompress(out.data(), &out_size, const_cast<char*>(data.data()),
                               static_cast<unsigned int>(data.size()), 9, 0, 30) != BZ_OK)
    throw BagError("bz2 compression failed");
  out.resize(out_size);
  return out;
}

std::string Lz4FrameCompress(const std::string& data) {
  std::string out(LZ4F_compressFrameBound(data.size(), nullptr), '\0');
  const size_t n = LZ4F_compressFrame(out.data(), out.size(), data.data(), data.size(), nullptr);
  if (LZ4F_isError(n)) throw BagError(std::string("lz4 compression failed: ") + LZ4F_getErrorName(n));
  out.resize(n);
  return out;
}

// ---- the bag ------------------------------------------------------------------------------------------

RosBag RosBag::Open(const std::string& path) {
  std::string bytes = ReadWholeFile(path);
  if (bytes.compare(0, 3, "BZh") == 0) bytes = Bz2StreamDecompress(bytes, path);
  if (bytes.size() < kMagicSize || bytes.compare(0, kMagicSize, kMagic) != 0) {
    if (bytes.compare(0, 8, "#ROSBAG ") == 0)
      throw BagError(path + ": bag format " + bytes.substr(8, bytes.find('\n') - 8) +
                     " is not supported (only V2.0, ROS 1)");
    throw BagError(path + ": not a ROS bag (no '#ROSBAG V2.0' line)");
  }
  RosBag bag;
  bag.path_ = path;
  bag.ReadRecords(reinterpret_cast<const uint8_t*>(bytes.data()) + kMagicSize, bytes.size() - kMagicSize,
                  kMagicSize, false);
  for (const BagMessage& m : bag.messages_) bag.Connection(m.connection);  // every message has one
  return bag;
}

void RosBag::ReadRecords(const uint8_t* data, size_t size, uint64_t base, bool in_chunk) {
  size_t i = 0;
  while (i < size) {
    const std::string where = path_ + ": " + (in_chunk ? "chunk byte " : "byte ") + std::to_string(base + i);
    if (size - i < 4) throw BagError(where + ": record cut short");
    const uint32_t header_len = ReadU32(data + i);
    if (header_len > size - i - 4) throw BagError(where + ": record header overruns the file");
    const auto h = ParseHeader(data + i + 4, header_len, where);
    size_t j = i + 4 + header_len;
    if (size - j < 4) throw BagError(where + ": record data length cut short");
    const uint32_t data_len = ReadU32(data + j);
    j += 4;
    if (data_len > size - j) throw BagError(where + ": record data overruns the file");
    const uint8_t* payload = data + j;
    const std::string& op = Require(h, "op", where);
    if (op.size() != 1) throw BagError(where + ": op field is not one byte");
    switch (op[0]) {
      case 0x05: {  // chunk
        const std::string& compression = Require(h, "compression", where);
        const std::string raw = ChunkContent(h, compression, payload, data_len, where);
        ++compressions_[compression];
        ReadRecords(reinterpret_cast<const uint8_t*>(raw.data()), raw.size(), 0, true);
        break;
      }
      case 0x07: {  // connection
        const uint32_t id = FieldU32(h, "conn", where);
        if (connection_index_.count(id)) break;  // repeated in the index section
        connection_index_[id] = connections_.size();
        connections_.push_back(ParseConnection(id, h, payload, data_len, where));
        break;
      }
      case 0x02: {  // message data
        BagMessage m;
        m.connection = FieldU32(h, "conn", where);
        const std::string& t = Require(h, "time", where);
        if (t.size() != 8) throw BagError(where + ": time field is not 8 bytes");
        const auto* tp = reinterpret_cast<const uint8_t*>(t.data());
        m.time_ns = int64_t(ReadU32(tp)) * 1000000000LL + ReadU32(tp + 4);
        m.data.assign(payload, payload + data_len);
        messages_.push_back(std::move(m));
        break;
      }
      case 0x03:  // bag header
      case 0x04:  // index data
      case 0x06:  // chunk info
        break;
      default:
        throw BagError(where + ": unknown record op 0x" + std::to_string(int(uint8_t(op[0]))));
    }
    i = j + data_len;
  }
}

const BagConnection& RosBag::Connection(uint32_t id) const {
  auto it = connection_index_.find(id);
  if (it == connection_index_.end())
    throw BagError(path_ + ": message on connection " + std::to_string(id) + ", which the bag never defines");
  return connections_[it->second];
}

const BagConnection* RosBag::FindTopic(const std::string& topic) const {
  for (const BagConnection& c : connections_)
    if (c.topic == topic) return &c;
  return nullptr;
}

RosValue RosBag::Decode(const BagMessage& message) const {
  const BagConnection& c = Connection(message.connection);
  auto it = schemas_.find(c.id);
  std::shared_ptr<RosSchema> schema;
  if (it == schemas_.end()) {
    if (c.definition.empty())
      throw BagError(path_ + ": topic " + c.topic + " (" + c.type + ") has no message_definition");
    schema = std::make_shared<RosSchema>(c.type, c.definition);
    const_cast<RosBag*>(this)->schemas_[c.id] = schema;
  } else {
    schema = it->second;
  }
  try {
    return schema->Decode(message.data.data(), message.data.size());
  } catch (const BagError& e) {
    throw BagError(path_ + ": topic " + c.topic + ": " + e.what());
  }
}

std::string RosBag::TopicList() const {
  std::string s;
  for (const BagConnection& c : connections_) s += (s.empty() ? "" : ", ") + c.topic + " (" + c.type + ")";
  return s.empty() ? "none" : s;
}

}  // namespace mcmt
