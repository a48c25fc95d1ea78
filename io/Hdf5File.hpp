// A small RAII wrapper over the HDF5 C API: every handle is closed by its destructor and
// every failure becomes an InputError that names the file and the object path.
#pragma once
#include <hdf5.h>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/Vec3.hpp"
#include "cosmology/Background.hpp"

namespace fountain::io::hdf5 {

// Owns one HDF5 identifier (file, group, dataset, attribute, dataspace, datatype) and
// closes it with the matching H5?close function.
class Id {
 public:
  using Closer = herr_t (*)(hid_t);
  Id() = default;
  Id(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  Id(Id&& other) noexcept : id_(std::exchange(other.id_, H5I_INVALID_HID)), closer_(other.closer_) {}
  Id& operator=(Id&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
      closer_ = other.closer_;
    }
    return *this;
  }
  ~Id() { reset(); }

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now and returns the status of the close call (negative on failure).
  herr_t close() {
    herr_t status = 0;
    if (id_ >= 0 && closer_ != nullptr) status = closer_(id_);
    id_ = H5I_INVALID_HID;
    return status;
  }
  void reset() noexcept { (void)close(); }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

// Switches off HDF5's automatic printing of its error stack (we report errors ourselves).
// Called by every entry point of this wrapper; cheap and idempotent.
void silence_hdf5_errors();

// The innermost message on HDF5's current error stack (then cleared), or "" if none.
std::string hdf5_error_detail();

// True if `path` is a readable HDF5 file (H5Fis_hdf5 > 0); false for anything else.
bool is_hdf5(const std::string& path);

// Shape and element type of a dataset, as found in the file.
struct DatasetInfo {
  std::vector<std::uint64_t> dims;  // empty for a scalar dataset
  H5T_class_t type_class = H5T_NO_CLASS;
  std::size_t type_size = 0;
  bool is_signed = false;  // integer types only

  std::uint64_t rows() const { return dims.empty() ? 1 : dims[0]; }
};

// A stretch of a dataset's rows, [first, first + count): the share of a file one MPI rank reads.
struct RowRange {
  std::uint64_t first = 0, count = 0;
};

using StringAttributes = std::vector<std::pair<std::string, std::string>>;

class File {
 public:
  enum class Mode { read, create };  // create truncates an existing file

  File(const std::string& path, Mode mode);
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  File(File&&) noexcept = default;
  File& operator=(File&&) noexcept = default;
  ~File() = default;  // closes quietly; call close() to see write errors

  // Closes the file, flushing it; throws if HDF5 reports a failure (e.g. a full disk).
  void close();

  const std::string& path() const { return path_; }
  hid_t id() const { return file_.get(); }

  // --- Queries ---------------------------------------------------------------------------
  // True if every link of the absolute object path ("/PartType0/Masses") exists.
  bool exists(const std::string& object) const;
  bool has_attribute(const std::string& object, const std::string& name) const;
  DatasetInfo dataset_info(const std::string& dataset) const;

  // --- Reading datasets --------------------------------------------------------------------
  // With `rows`, only those rows are read (a range past the dataset's end is an error).
  // Every element converted to double (any float or integer type), row-major and flat.
  std::vector<double> read_doubles(const std::string& dataset, const RowRange* rows = nullptr) const;
  // An N x 3 dataset as N vectors (throws on any other shape).
  std::vector<Vec3> read_vec3(const std::string& dataset, const RowRange* rows = nullptr) const;
  // Any integer type as uint64; negative values and non-integer types are errors.
  std::vector<std::uint64_t> read_uint64(const std::string& dataset, const RowRange* rows = nullptr) const;
  // A string dataset (fixed or variable length, scalar).
  std::string read_string(const std::string& dataset) const;

  // --- Reading attributes (scalar or array) ------------------------------------------------
  std::vector<double> read_attribute_doubles(const std::string& object, const std::string& name) const;
  // A scalar (or one-element array) attribute as double.
  double read_attribute_double(const std::string& object, const std::string& name) const;
  // Non-negative integers (any integer type; floats only if they hold whole numbers).
  std::vector<std::uint64_t> read_attribute_uint64(const std::string& object, const std::string& name) const;
  std::vector<std::int64_t> read_attribute_int64(const std::string& object, const std::string& name) const;
  std::string read_attribute_string(const std::string& object, const std::string& name) const;

  // --- Writing -----------------------------------------------------------------------------
  // Creates the group (its parent must exist); a no-op if it already exists.
  void create_group(const std::string& group);

  // (Spans: a store's field is written where it lies, never copied.)
  void write_dataset(const std::string& dataset, std::span<const double> values,
                     const StringAttributes& attributes = {});
  void write_dataset(const std::string& dataset, std::span<const Vec3> values,
                     const StringAttributes& attributes = {});
  void write_dataset(const std::string& dataset, std::span<const std::uint64_t> values,
                     const StringAttributes& attributes = {});
  void write_dataset(const std::string& dataset, std::span<const std::int32_t> values,
                     const StringAttributes& attributes = {});
  // Datasets of values that are not in memory as one array (scaled or gathered on the way),
  // filled a piece of rows at a time through one small buffer: fill(first, out) writes rows
  // first, first + 1, ... into `out` (row-major, whole rows). Float64 rows of `columns` values
  // (rank 1 where that is 1, else rows x columns), or uint64 scalars. The file holds the same
  // dataset as write_dataset's of the whole array.
  using DoublePieceFill = std::function<void(std::size_t first, std::span<double> out)>;
  using IdPieceFill = std::function<void(std::size_t first, std::span<std::uint64_t> out)>;
  void write_dataset_in_pieces(const std::string& dataset, std::size_t rows, std::size_t columns,
                               const DoublePieceFill& fill);
  void write_dataset_in_pieces(const std::string& dataset, std::size_t rows, const IdPieceFill& fill);
  // Datasets whose rows arrive in runs from several sources (a snapshot gathered from MPI
  // ranks): created whole first, then written a run of rows at a time, in any order. Float64
  // rows of `columns` values (rank 1 where that is 1), uint64 or int32 scalars; the file holds
  // the same dataset as write_dataset's of the whole array.
  enum class RowType { float64, uint64, int32 };
  void create_rows_dataset(const std::string& dataset, RowType type, std::size_t rows, std::size_t columns = 1);
  void write_rows(const std::string& dataset, std::size_t first, std::span<const double> values, std::size_t columns = 1);
  void write_rows(const std::string& dataset, std::size_t first, std::span<const std::uint64_t> values);
  void write_rows(const std::string& dataset, std::size_t first, std::span<const std::int32_t> values);
  // Two-dimensional tables, row-major, `columns` values per row (GADGET's GroupMassType).
  void write_table(const std::string& dataset, const std::vector<double>& values, std::size_t columns,
                   const StringAttributes& attributes = {});
  void write_table(const std::string& dataset, const std::vector<std::uint64_t>& values, std::size_t columns,
                   const StringAttributes& attributes = {});
  // A scalar fixed-length string dataset (for long texts that do not fit an attribute).
  void write_string_dataset(const std::string& dataset, const std::string& text);

  // Attributes on any object (group or dataset); an existing attribute is replaced.
  void write_attribute(const std::string& object, const std::string& name, double value);
  void write_attribute(const std::string& object, const std::string& name, int value);
  void write_attribute(const std::string& object, const std::string& name, std::int64_t value);
  void write_attribute(const std::string& object, const std::string& name, const std::string& value);
  void write_attribute(const std::string& object, const std::string& name, const char* value) {
    write_attribute(object, name, std::string(value));
  }
  void write_attribute(const std::string& object, const std::string& name, const std::vector<double>& values);
  void write_attribute(const std::string& object, const std::string& name, const std::vector<std::int32_t>& values);
  void write_attribute(const std::string& object, const std::string& name, const std::vector<std::uint32_t>& values);
  void write_attribute(const std::string& object, const std::string& name, const std::vector<std::int64_t>& values);
  void write_attribute(const std::string& object, const std::string& name, const std::vector<std::uint64_t>& values);

  // Throws InputError "<file>: <object>: <what>" (plus HDF5's own detail if any).
  [[noreturn]] void fail(const std::string& object, const std::string& what) const;

 private:
  Id open_object(const std::string& object) const;
  Id open_dataset(const std::string& dataset) const;
  Id open_attribute(const std::string& object, const std::string& name) const;
  void write_numeric_dataset(const std::string& dataset, hid_t file_type, hid_t memory_type,
                             const std::vector<hsize_t>& dims, const void* data,
                             const StringAttributes& attributes);
  Id create_dataset(const std::string& dataset, hid_t file_type, const std::vector<hsize_t>& dims);
  // The file and memory selections of `rows` of a dataset (all of it without `rows`), and
  // how many elements they hold.
  struct Selection {
    Id file, memory;
    std::size_t elements = 0;
  };
  Selection select_rows(const Id& ds, const std::string& dataset, const RowRange* rows) const;
  template <class T>
  void write_pieces(const std::string& dataset, hid_t file_type, hid_t memory_type, std::size_t rows,
                    std::size_t columns, const std::function<void(std::size_t, std::span<T>)>& fill);
  void write_rows_of(const std::string& dataset, hid_t memory_type, std::size_t first, std::size_t rows,
                     std::size_t columns, const void* data);
  void write_numeric_attribute(const std::string& object, const std::string& name, hid_t file_type,
                               hid_t memory_type, const std::vector<hsize_t>& dims, const void* data);

  std::string path_;
  Id file_;
};

// --- Helpers shared by the GADGET/SWIFT-layout writers ---------------------------------------

// Creates `path` + ".tmp", lets `fill` write into it, closes (flushes) it and renames it to
// `path`, so a failed or interrupted write never leaves a half-written file under the final
// name. On any failure the temporary file is removed and InputError
// "cannot create <what> <path>: <reason>" is thrown. A missing or non-folder parent is
// reported as such before anything is created.
void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<void(File&)>& fill);

// The same in steps, for a file written over a while (a snapshot whose particles arrive from
// other ranks): the constructor checks the folder and creates `path` + ".tmp", write() runs
// each part of the filling, commit() closes and renames. A failure in any of them, or
// destruction before commit(), removes the temporary file; the failures throw InputError
// "cannot create <what> <path>: <reason>".
class AtomicFile {
 public:
  AtomicFile(std::string path, std::string what);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  void write(const std::function<void(File&)>& part);
  void commit();

 private:
  [[noreturn]] void fail(std::string reason);
  std::string path_, tmp_, prefix_;
  std::unique_ptr<File> file_;
};

// Writes the GADGET-2 style /Header group for `counts[t]` particles of each type t:
// NumPart_ThisFile (uint32[6], uint64[6] if a count is >= 2^32), NumPart_Total (uint32[6], low
// words) with NumPart_Total_HighWord (uint32[6]), MassTable (zeros: masses go in the Masses
// datasets), Time, BoxSize (`box_size`: 1 or 3 values), NumFilesPerSnapshot = 1, Dimension = 3,
// Flag_* = 0 except Flag_DoublePrecision = 1 (every dataset is float64). Without `cosmology`:
// Redshift = 0, Omega0 = OmegaLambda = 0 and HubbleParam = 1 (GADGET's non-cosmological
// header); with it, `time` is the scale factor and Redshift, Omega0, OmegaLambda, OmegaBaryon
// and HubbleParam are the run's.
void write_gadget_header(File& file, const std::array<std::uint64_t, 6>& counts, const std::vector<double>& box_size,
                         double time, const cosmology::CosmologyParams* cosmology = nullptr);

}  // namespace fountain::io::hdf5
