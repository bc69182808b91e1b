// ROS 1 message definitions and serialisation (little-endian; string = uint32 length + bytes; T[] =
// uint32 count + elements; T[N] = N elements; time/duration = two 32-bit integers secs, nsecs).
#include <cstring>
#include <set>
#include <sstream>

#include "import/rosbag.h"

namespace mcmt {
namespace {

const std::set<std::string>& Builtins() {
  static const std::set<std::string> kBuiltins = {
      "bool",   "int8",    "uint8",   "int16",  "uint16", "int32",    "uint32", "int64",
      "uint64", "float32", "float64", "string", "time",   "duration", "char",   "byte"};
  return kBuiltins;
}

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

std::string PackageOf(const std::string& type) {
  const size_t slash = type.find('/');
  return slash == std::string::npos ? "" : type.substr(0, slash);
}

// One field line ("float64[4] x  # comment"); false for comments, blank lines and constants.
bool ParseFieldLine(const std::string& raw, RosField* field, const std::string& where) {
  const size_t hash = raw.find('#'), eq = raw.find('=');
  if (eq != std::string::npos && (hash == std::string::npos || eq < hash)) return false;  // constant
  const std::string line = Trim(raw.substr(0, hash));
  if (line.empty()) return false;
  std::istringstream in(line);
  std::string type, name;
  if (!(in >> type >> name)) throw BagError(where + ": cannot read the field line '" + line + "'");
  field->name = name;
  field->array_size = -1;
  const size_t bracket = type.find('[');
  if (bracket != std::string::npos) {
    const std::string n = type.substr(bracket + 1, type.size() - bracket - 2);
    field->array_size = n.empty() ? 0 : std::stoi(n);
    type = type.substr(0, bracket);
  }
  field->type = type;
  return true;
}

class Cursor {
 public:
  Cursor(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  const uint8_t* Take(size_t n, const std::string& what) {
    if (n > size_ - pos_)
      throw BagError("message cut short reading " + what + " (byte " + std::to_string(pos_) + " of " +
                     std::to_string(size_) + ")");
    const uint8_t* p = data_ + pos_;
    pos_ += n;
    return p;
  }
  template <typename T>
  T Read(const std::string& what) {
    T v;
    std::memcpy(&v, Take(sizeof(T), what), sizeof(T));  // little-endian host (x86, ARM)
    return v;
  }
  size_t remaining() const { return size_ - pos_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

RosValue Number(double d, bool is_integer, int64_t i) {
  RosValue v;
  v.number = d;
  v.is_integer = is_integer;
  v.integer = i;
  return v;
}

template <typename T>
RosValue ReadInteger(Cursor* c, const std::string& what) {
  const T x = c->Read<T>(what);
  return Number(static_cast<double>(x), true, static_cast<int64_t>(x));
}

RosValue DecodeBuiltin(const std::string& type, Cursor* c, const std::string& what) {
  if (type == "bool" || type == "uint8" || type == "char") return ReadInteger<uint8_t>(c, what);
  if (type == "int8" || type == "byte") return ReadInteger<int8_t>(c, what);
  if (type == "int16") return ReadInteger<int16_t>(c, what);
  if (type == "uint16") return ReadInteger<uint16_t>(c, what);
  if (type == "int32") return ReadInteger<int32_t>(c, what);
  if (type == "uint32") return ReadInteger<uint32_t>(c, what);
  if (type == "int64") return ReadInteger<int64_t>(c, what);
  if (type == "uint64") return ReadInteger<uint64_t>(c, what);
  if (type == "float32") return Number(c->Read<float>(what), false, 0);
  if (type == "float64") return Number(c->Read<double>(what), false, 0);
  if (type == "string") {
    const uint32_t n = c->Read<uint32_t>(what);
    RosValue v;
    v.kind = RosValue::Kind::kString;
    v.text.assign(reinterpret_cast<const char*>(c->Take(n, what)), n);
    return v;
  }
  // time, duration
  RosValue v;
  v.kind = RosValue::Kind::kMessage;
  v.fields.emplace_back("secs",
                        type == "time" ? ReadInteger<uint32_t>(c, what) : ReadInteger<int32_t>(c, what));
  v.fields.emplace_back("nsecs",
                        type == "time" ? ReadInteger<uint32_t>(c, what) : ReadInteger<int32_t>(c, what));
  return v;
}

}  // namespace

// ---- RosValue -----------------------------------------------------------------------------------------

const RosValue* RosValue::Find(const std::string& name) const {
  for (const auto& [n, v] : fields)
    if (n == name) return &v;
  return nullptr;
}

const RosValue& RosValue::At(const std::string& path) const {
  const RosValue* v = this;
  size_t start = 0;
  while (start <= path.size()) {
    const size_t dot = path.find('.', start);
    const std::string name = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    const RosValue* next = v->kind == Kind::kMessage ? v->Find(name) : nullptr;
    if (!next) throw BagError("message has no field '" + path + "'");
    v = next;
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return *v;
}

double RosValue::AsDouble() const {
  if (kind != Kind::kNumber) throw BagError("field is not a number");
  return number;
}

int64_t RosValue::AsInt() const {
  if (kind != Kind::kNumber || !is_integer) throw BagError("field is not an integer");
  return integer;
}

// ---- RosSchema ----------------------------------------------------------------------------------------

RosSchema::RosSchema(const std::string& type, const std::string& definition) : type_(type) {
  std::istringstream in(definition);
  std::string line;
  RosMessageType current;
  current.name = type;
  auto finish = [&]() { types_[current.name] = current; };
  while (std::getline(in, line)) {
    if (line.compare(0, 3, "===") == 0) {
      finish();
      current = RosMessageType();
      continue;
    }
    const std::string trimmed = Trim(line);
    if (trimmed.compare(0, 4, "MSG:") == 0) {
      current.name = Trim(trimmed.substr(4));
      continue;
    }
    RosField field;
    if (ParseFieldLine(line, &field, type + " definition")) current.fields.push_back(field);
  }
  finish();
  // Resolve every field's type to a builtin or a defined "pkg/Name".
  for (auto& [name, t] : types_)
    for (RosField& f : t.fields) f.type = Resolve(f.type, PackageOf(name));
}

std::string RosSchema::Resolve(const std::string& field_type, const std::string& package) const {
  if (Builtins().count(field_type)) return field_type;
  std::string full = field_type;
  if (field_type == "Header")
    full = "std_msgs/Header";
  else if (field_type.find('/') == std::string::npos)
    full = package + "/" + field_type;
  if (!types_.count(full))
    throw BagError(type_ + ": the message definition uses " + full + " but does not define it");
  return full;
}

const RosMessageType& RosSchema::Get(const std::string& type) const {
  auto it = types_.find(type);
  if (it == types_.end()) throw BagError(type_ + ": no definition of " + type);
  return it->second;
}

namespace {

RosValue DecodeType(const RosSchema& schema, const std::string& type, Cursor* c, const std::string& what);

RosValue DecodeOne(const RosSchema& schema, const std::string& type, Cursor* c, const std::string& what) {
  if (Builtins().count(type)) return DecodeBuiltin(type, c, what);
  return DecodeType(schema, type, c, what);
}

RosValue DecodeType(const RosSchema& schema, const std::string& type, Cursor* c, const std::string& what) {
  RosValue v;
  v.kind = RosValue::Kind::kMessage;
  for (const RosField& f : schema.Get(type).fields) {
    const std::string field_what = what.empty() ? f.name : what + "." + f.name;
    if (f.array_size < 0) {
      v.fields.emplace_back(f.name, DecodeOne(schema, f.type, c, field_what));
      continue;
    }
    RosValue array;
    array.kind = RosValue::Kind::kArray;
    const uint32_t n = f.array_size > 0 ? uint32_t(f.array_size) : c->Read<uint32_t>(field_what);
    if (n > c->remaining()) throw BagError("array " + field_what + " of " + std::to_string(n) + " overruns");
    array.items.reserve(n);
    for (uint32_t i = 0; i < n; ++i) array.items.push_back(DecodeOne(schema, f.type, c, field_what));
    v.fields.emplace_back(f.name, std::move(array));
  }
  return v;
}

}  // namespace

RosValue RosSchema::Decode(const uint8_t* data, size_t size) const {
  Cursor c(data, size);
  RosValue v = DecodeType(*this, type_, &c, "");
  if (c.remaining() != 0)
    throw BagError(type_ + ": " + std::to_string(c.remaining()) + " bytes left after the message");
  return v;
}

}  // namespace mcmt
