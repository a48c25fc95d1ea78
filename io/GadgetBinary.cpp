#include "io/GadgetBinary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>

#include "core/Error.hpp"

namespace fountain::io {

namespace {

constexpr std::uint32_t kHeaderBytes = 256;

template <class T>
T swapped(T value) {
  std::array<unsigned char, sizeof(T)> b;
  std::memcpy(b.data(), &value, sizeof(T));
  std::reverse(b.begin(), b.end());
  std::memcpy(&value, b.data(), sizeof(T));
  return value;
}

// Values at byte offsets of a record, in the file's byte order.
struct RecordView {
  const std::vector<char>& bytes;
  bool swap;
  template <class T>
  T at(std::size_t offset) const {
    T value;
    std::memcpy(&value, bytes.data() + offset, sizeof(T));
    return swap ? swapped(value) : value;
  }
};

// Reads the records of one file in order.
class RecordReader {
 public:
  explicit RecordReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw InputError(fmt::format("{}: cannot open the GADGET binary file", path));
    std::uint32_t first = 0;
    if (!in_.read(reinterpret_cast<char*>(&first), 4))
      throw InputError(fmt::format("{}: too short for a GADGET binary file", path));
    if (first == kHeaderBytes || first == 8) {
      swap_ = false;
    } else if (swapped(first) == kHeaderBytes || swapped(first) == 8) {
      swap_ = true;
      first = swapped(first);
    } else {
      throw InputError(fmt::format("{}: not a GADGET binary file (its first record marker is {}, expected 256, or 8 "
                                   "for format 2)",
                                   path, first));
    }
    format_ = first == 8 ? 2 : 1;
    in_.seekg(0, std::ios::end);
    file_bytes_ = static_cast<std::uint64_t>(in_.tellg());
    in_.seekg(0);
  }
  bool swap() const { return swap_; }
  int format() const { return format_; }
  bool at_end() {
    return in_.peek() == std::char_traits<char>::eof();
  }
  // The next block's payload; `block` names it in errors.
  std::vector<char> next(const char* block) {
    if (format_ == 2) {
      const std::vector<char> label = record(block);
      if (label.size() != 8)
        throw InputError(fmt::format("{}: block {}: format 2 label record of {} bytes, expected 8", path_, block,
                                     label.size()));
    }
    return record(block);
  }

 private:
  std::uint32_t marker(const char* block) {
    std::uint32_t m = 0;
    if (!in_.read(reinterpret_cast<char*>(&m), 4))
      throw InputError(fmt::format("{}: block {} is missing (the file ends before it)", path_, block));
    return swap_ ? swapped(m) : m;
  }
  std::vector<char> record(const char* block) {
    const std::uint32_t size = marker(block);
    // A corrupt marker must not ask for gigabytes: the record cannot be longer than the file.
    const auto at = static_cast<std::uint64_t>(in_.tellg());
    if (static_cast<std::uint64_t>(size) + 4 > file_bytes_ - std::min(at, file_bytes_))
      throw InputError(fmt::format("{}: block {} is truncated ({} bytes announced, {} left in the file)", path_, block,
                                   size, file_bytes_ - std::min(at, file_bytes_)));
    std::vector<char> payload(size);
    if (!in_.read(payload.data(), static_cast<std::streamsize>(size)))
      throw InputError(fmt::format("{}: block {} is truncated ({} bytes announced)", path_, block, size));
    const std::uint32_t end = marker(block);
    if (end != size)
      throw InputError(fmt::format("{}: block {}: record markers disagree ({} and {}): a corrupt file", path_, block,
                                   size, end));
    return payload;
  }

  std::string path_;
  std::ifstream in_;
  bool swap_ = false;
  int format_ = 1;
  std::uint64_t file_bytes_ = 0;
};

GadgetHeader parse_header(const std::vector<char>& bytes, bool swap, const std::string& path) {
  if (bytes.size() != kHeaderBytes)
    throw InputError(fmt::format("{}: block HEAD has {} bytes, expected 256", path, bytes.size()));
  const RecordView r{bytes, swap};
  GadgetHeader h;
  for (int t = 0; t < 6; ++t) {
    h.count_this_file[t] = r.at<std::uint32_t>(4 * t);
    h.mass_table[t] = r.at<double>(24 + 8 * t);
    h.count_total[t] = r.at<std::uint32_t>(96 + 4 * t) +
                       (static_cast<std::uint64_t>(r.at<std::uint32_t>(168 + 4 * t)) << 32);
  }
  h.time = r.at<double>(72);
  h.redshift = r.at<double>(80);
  h.flag_sfr = r.at<std::int32_t>(88);
  h.flag_feedback = r.at<std::int32_t>(92);
  h.flag_cooling = r.at<std::int32_t>(120);
  h.files = r.at<std::int32_t>(124);
  h.box_size = r.at<double>(128);
  h.omega0 = r.at<double>(136);
  h.omega_lambda = r.at<double>(144);
  h.hubble_param = r.at<double>(152);
  h.flag_stellar_age = r.at<std::int32_t>(160);
  h.flag_metals = r.at<std::int32_t>(164);
  h.flag_entropy_ics = r.at<std::int32_t>(192);
  for (int t = 0; t < 6; ++t)
    if (!(h.mass_table[t] >= 0.0) || !std::isfinite(h.mass_table[t]))
      throw InputError(fmt::format("{}: header: the mass table's entry for type {} is {}", path, t, h.mass_table[t]));
  return h;
}

// Reals of `count` values of `per` components each from a block of 4- or 8-byte reals.
std::vector<double> reals(const std::vector<char>& bytes, std::uint64_t count, int per, bool swap,
                          const std::string& path, const char* block) {
  const std::uint64_t values = count * static_cast<std::uint64_t>(per);
  std::vector<double> out(values);
  if (values == 0) return out;
  const RecordView r{bytes, swap};
  if (bytes.size() == values * 4) {
    for (std::uint64_t k = 0; k < values; ++k) out[k] = static_cast<double>(r.at<float>(4 * k));
  } else if (bytes.size() == values * 8) {
    for (std::uint64_t k = 0; k < values; ++k) out[k] = r.at<double>(8 * k);
  } else {
    throw InputError(fmt::format("{}: block {} has {} bytes, which is neither 4 nor 8 bytes for each of its {} values "
                                 "(the header's particle counts disagree with the block)",
                                 path, block, bytes.size(), values));
  }
  for (std::uint64_t k = 0; k < values; ++k)
    if (!std::isfinite(out[k]))
      throw InputError(fmt::format("{}: block {}: value {} (particle {} of the file) is not finite", path, block, k,
                                   k / static_cast<std::uint64_t>(per)));
  return out;
}

void read_file(const std::string& path, GadgetSnapshot& out, bool first_file) {
  RecordReader in(path);
  const GadgetHeader h = parse_header(in.next("HEAD"), in.swap(), path);
  if (first_file) {
    out.header = h;
    out.header.count_this_file = {};
  }
  std::uint64_t n = 0;
  for (int t = 0; t < 6; ++t) n += h.count_this_file[t];
  const std::vector<double> pos = reals(in.next("POS"), n, 3, in.swap(), path, "POS");
  const std::vector<double> vel = reals(in.next("VEL"), n, 3, in.swap(), path, "VEL");
  const std::vector<char> ids = in.next("ID");
  const RecordView id_view{ids, in.swap()};
  const bool long_ids = n > 0 && ids.size() == n * 8;
  if (n > 0 && !long_ids && ids.size() != n * 4)
    throw InputError(fmt::format("{}: block ID has {} bytes for {} particles (neither 4 nor 8 bytes each)", path,
                                 ids.size(), n));
  std::uint64_t variable = 0;
  for (int t = 0; t < 6; ++t)
    if (h.count_this_file[t] > 0 && h.mass_table[t] == 0.0) variable += h.count_this_file[t];
  const std::vector<double> masses =
      variable > 0 ? reals(in.next("MASS"), variable, 1, in.swap(), path, "MASS") : std::vector<double>{};
  std::vector<double> u;
  if (h.count_this_file[0] > 0 && !in.at_end()) u = reals(in.next("U"), h.count_this_file[0], 1, in.swap(), path, "U");

  std::uint64_t k = 0, m = 0;
  for (int t = 0; t < 6; ++t) {
    GadgetParticles& p = out.types[static_cast<std::size_t>(t)];
    for (std::uint64_t i = 0; i < h.count_this_file[t]; ++i, ++k) {
      p.x.push_back({pos[3 * k], pos[3 * k + 1], pos[3 * k + 2]});
      p.v.push_back({vel[3 * k], vel[3 * k + 1], vel[3 * k + 2]});
      p.id.push_back(long_ids ? id_view.at<std::uint64_t>(8 * k) : id_view.at<std::uint32_t>(4 * k));
      const double mass = h.mass_table[t] > 0.0 ? h.mass_table[t] : masses[m++];
      if (!(mass > 0.0))
        throw InputError(fmt::format("{}: particle ID {} (type {}) has mass {}", path, p.id.back(), t, mass));
      p.mass.push_back(mass);
    }
    out.header.count_this_file[t] += h.count_this_file[t];
  }
  if (!u.empty()) {
    GadgetParticles& gas = out.types[0];
    gas.u.insert(gas.u.end(), u.begin(), u.end());
  }
}

template <class T>
void put(std::vector<char>& b, T value, bool swap) {
  if (swap) value = swapped(value);
  const auto* p = reinterpret_cast<const char*>(&value);
  b.insert(b.end(), p, p + sizeof(T));
}

void write_record(std::ofstream& out, const std::vector<char>& payload, const char* label, const GadgetBinaryLayout& l) {
  auto marker = [&](std::uint32_t m) {
    if (l.swap_bytes) m = swapped(m);
    out.write(reinterpret_cast<const char*>(&m), 4);
  };
  if (l.format == 2) {
    std::vector<char> tag(8, ' ');
    std::memcpy(tag.data(), label, std::min<std::size_t>(4, std::strlen(label)));
    std::uint32_t next = static_cast<std::uint32_t>(payload.size() + 8);
    if (l.swap_bytes) next = swapped(next);
    std::memcpy(tag.data() + 4, &next, 4);
    marker(8);
    out.write(tag.data(), 8);
    marker(8);
  }
  marker(static_cast<std::uint32_t>(payload.size()));
  out.write(payload.data(), static_cast<std::streamsize>(payload.size()));
  marker(static_cast<std::uint32_t>(payload.size()));
}

}  // namespace

bool is_gadget_binary(const std::string& path) {
  const std::string file = std::filesystem::exists(path) ? path : path + ".0";
  std::ifstream in(file, std::ios::binary);
  std::uint32_t first = 0;
  if (!in.read(reinterpret_cast<char*>(&first), 4)) return false;
  return first == kHeaderBytes || swapped(first) == kHeaderBytes || first == 8 || swapped(first) == 8;
}

GadgetSnapshot read_gadget_binary(const std::string& path) {
  GadgetSnapshot out;
  if (std::filesystem::exists(path)) {
    read_file(path, out, true);
  } else {
    if (!std::filesystem::exists(path + ".0"))
      throw InputError(fmt::format("{}: no such GADGET binary file (nor {}.0)", path, path));
    read_file(path + ".0", out, true);
    const int files = out.header.files;
    if (files < 1 || files > 1 << 20)
      throw InputError(fmt::format("{}.0: header: number of files {} is not sensible", path, files));
    for (int f = 1; f < files; ++f) read_file(fmt::format("{}.{}", path, f), out, false);
  }
  for (int t = 0; t < 6; ++t)
    if (out.header.count_this_file[t] != out.header.count_total[t])
      throw InputError(fmt::format("{}: the files hold {} particles of type {} but the header's total is {}", path,
                                   out.header.count_this_file[t], t, out.header.count_total[t]));
  if (!out.types[0].u.empty() && out.types[0].u.size() != out.types[0].x.size())
    throw InputError(fmt::format("{}: block U is missing from some of the files", path));
  return out;
}

void write_gadget_binary(const std::string& path, const GadgetSnapshot& s, const GadgetBinaryLayout& l) {
  if (l.format != 1 && l.format != 2) throw InputError(fmt::format("{}: GADGET binary format {} unknown", path, l.format));
  if (l.files < 1) throw InputError(fmt::format("{}: at least one file", path));
  const bool swap = l.swap_bytes;
  for (int f = 0; f < l.files; ++f) {
    const std::string file = l.files == 1 ? path : fmt::format("{}.{}", path, f);
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(fmt::format("{}: cannot create the file", file));
    std::array<std::size_t, 6> first{}, count{};
    for (int t = 0; t < 6; ++t) {
      const std::size_t n = s.types[static_cast<std::size_t>(t)].x.size();
      first[t] = n * static_cast<std::size_t>(f) / static_cast<std::size_t>(l.files);
      count[t] = n * static_cast<std::size_t>(f + 1) / static_cast<std::size_t>(l.files) - first[t];
    }
    std::vector<char> head;
    for (int t = 0; t < 6; ++t) put<std::uint32_t>(head, static_cast<std::uint32_t>(count[t]), swap);
    for (int t = 0; t < 6; ++t) put<double>(head, s.header.mass_table[t], swap);
    put<double>(head, s.header.time, swap);
    put<double>(head, s.header.redshift, swap);
    put<std::int32_t>(head, s.header.flag_sfr, swap);
    put<std::int32_t>(head, s.header.flag_feedback, swap);
    for (int t = 0; t < 6; ++t)
      put<std::uint32_t>(head, static_cast<std::uint32_t>(s.types[static_cast<std::size_t>(t)].x.size() & 0xffffffffu), swap);
    put<std::int32_t>(head, s.header.flag_cooling, swap);
    put<std::int32_t>(head, l.files, swap);
    put<double>(head, s.header.box_size, swap);
    put<double>(head, s.header.omega0, swap);
    put<double>(head, s.header.omega_lambda, swap);
    put<double>(head, s.header.hubble_param, swap);
    put<std::int32_t>(head, s.header.flag_stellar_age, swap);
    put<std::int32_t>(head, s.header.flag_metals, swap);
    for (int t = 0; t < 6; ++t)
      put<std::uint32_t>(head, static_cast<std::uint32_t>(static_cast<std::uint64_t>(s.types[static_cast<std::size_t>(t)].x.size()) >> 32), swap);
    put<std::int32_t>(head, s.header.flag_entropy_ics, swap);
    put<std::int32_t>(head, l.double_precision ? 1 : 0, swap);  // MUSIC's flag_doubleprecision
    head.resize(kHeaderBytes, 0);
    write_record(out, head, "HEAD", l);

    auto real = [&](std::vector<char>& b, double v) {
      if (l.double_precision)
        put<double>(b, v, swap);
      else
        put<float>(b, static_cast<float>(v), swap);
    };
    std::vector<char> pos, vel, ids, mass, u;
    for (int t = 0; t < 6; ++t) {
      const GadgetParticles& p = s.types[static_cast<std::size_t>(t)];
      for (std::size_t i = first[t]; i < first[t] + count[t]; ++i) {
        for (int d = 0; d < 3; ++d) real(pos, p.x[i][d]);
        for (int d = 0; d < 3; ++d) real(vel, p.v[i][d]);
        if (l.long_ids)
          put<std::uint64_t>(ids, p.id[i], swap);
        else
          put<std::uint32_t>(ids, static_cast<std::uint32_t>(p.id[i]), swap);
        if (s.header.mass_table[t] == 0.0) real(mass, p.mass[i]);
        if (t == 0 && !p.u.empty()) real(u, p.u[i]);
      }
    }
    write_record(out, pos, "POS", l);
    write_record(out, vel, "VEL", l);
    write_record(out, ids, "ID", l);
    if (!mass.empty()) write_record(out, mass, "MASS", l);
    if (!u.empty()) write_record(out, u, "U", l);
    if (!out) throw InputError(fmt::format("{}: writing failed (disk full?)", file));
  }
}

}  // namespace fountain::io
