// .pcd files: reading through PCL's reader (every PCD encoding PCL knows), writing labelled
// voxel clouds.
#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/conversions.h>
#include <pcl/exceptions.h>
#include <pcl/io/pcd_io.h>

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <istream>
#include <iterator>
#include <optional>
#include <set>
#include <sstream>
#include <string>

#include "occseg/error.hpp"
#include "occseg/file_read.hpp"
#include "occseg/file_write.hpp"
#include "occseg/pcd.hpp"
#include "occseg/pcl_cloud.hpp"

namespace occseg {

namespace {

[[noreturn]] void bad_file(const std::string& path, const std::string& why) {
  throw Error(Status::format, "'" + path + "' is not a valid .pcd file: " + why);
}

// The keywords of a PCD header line, as PCL's header parser knows them.
constexpr const char* kHeaderKeys[] = {"VERSION", "FIELDS", "COLUMNS",   "SIZE",   "TYPE", "COUNT",
                                       "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};

// PCL reads x, y, z by name; a file without them as single float32 fields would give zeros.
void check_xyz_fields(const std::string& path, const pcl::PCLPointCloud2& blob) {
  for (const char* name : {"x", "y", "z"}) {
    bool found = false;
    for (const pcl::PCLPointField& f : blob.fields) {
      if (f.name != name) continue;
      if (f.datatype != pcl::PCLPointField::FLOAT32 || f.count != 1)
        bad_file(path, std::string("field '") + name + "' is not a single float32");
      found = true;
    }
    if (!found) bad_file(path, std::string("it has no '") + name + "' field");
  }
  const std::size_t n = std::size_t(blob.width) * blob.height;
  if (blob.data.size() < n * blob.point_step) bad_file(path, "data is shorter than WIDTH x HEIGHT points");
  // pcl::fromPCLPointCloud2 reads row r at r x row_step. PCL's header parser sets row_step when it
  // reads WIDTH and point_step from the fields as they stand at the end: a header listing its
  // fields again after WIDTH left rows longer than the data (found by fuzz_pcd). check_header
  // refuses repeated keys; this holds whatever else makes PCL's parse differ from it.
  if (std::size_t(blob.row_step) != std::size_t(blob.width) * blob.point_step)
    bad_file(path, "its rows are " + std::to_string(blob.row_step) + " bytes apart, not WIDTH x " +
                       std::to_string(blob.point_step) + " bytes");
  for (const pcl::PCLPointField& f : blob.fields)
    if (std::size_t(f.offset) + std::size_t(pcl::getFieldSize(f.datatype)) * f.count > blob.point_step)
      bad_file(path, "field '" + printable(f.name) + "' lies past the end of its point");
}

// PCL's reader trusts the header (a file without fields or sizes crashes it), so the header
// is checked here first: consistent field lists, WIDTH x HEIGHT = POINTS, and enough bytes for
// the binary encodings.
void check_header(const std::string& path, const std::string& bytes) {
  BytesBuf buf(bytes);
  std::istream in(&buf);
  std::size_t nfields = 0, nsize = 0, ntype = 0, ncount = 0, point_bytes = 0, width = 0, height = 1, points = 0;
  std::vector<std::size_t> sizes, counts;
  bool have_width = false, have_points = false;
  std::set<std::string> seen;  // the header keys met so far
  std::string line, data;
  for (int lines = 0; data.empty() && std::getline(in, line); ++lines) {
    if (lines > 1000) bad_file(path, "no DATA line in the first 1000 lines");
    if (line.empty()) continue;  // the one kind of line PCL skips besides comments
    // PCL ends its header at the first line it does not know, and then crashes on the fields
    // it has not read: such lines are refused here.
    if (std::isspace(static_cast<unsigned char>(line[0])))
      bad_file(path, "header line " + std::to_string(lines + 1) + " starts with a blank");
    if (line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key, v;
    if (!(ls >> key) || key[0] == '#') continue;
    // PCL acts on each header line as it comes (POINTS sizes its data, WIDTH its rows from the
    // fields so far), so a key given twice leaves PCL's cloud unlike the one checked here (found by
    // fuzz_pcd: a 40 GB allocation from a first POINTS line, rows past the data). No writer repeats one.
    const bool known =
        std::any_of(std::begin(kHeaderKeys), std::end(kHeaderKeys), [&](const char* k) { return key == k; });
    if (known && !seen.insert(key == "COLUMNS" ? "FIELDS" : key).second)
      bad_file(path, "header field " + key + " is given twice (line " + std::to_string(lines + 1) + ")");
    std::vector<std::string> vals;
    while (ls >> v) vals.push_back(v);
    // PCL holds WIDTH, HEIGHT, POINTS and COUNT in 32 bits: a larger value cannot be meant.
    auto number = [&](const std::string& t) -> std::size_t {
      if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos || t.size() > 10 ||
          std::stoull(t) > 0xffffffffull)
        bad_file(path, printable(key) + " value '" + printable(t) + "' is not a count (0 to 4294967295)");
      return std::stoull(t);
    };
    if (key == "FIELDS" || key == "COLUMNS") nfields = vals.size();
    else if (key == "SIZE") {
      nsize = vals.size();
      for (const auto& t : vals) {
        sizes.push_back(number(t));
        if (sizes.back() != 1 && sizes.back() != 2 && sizes.back() != 4 && sizes.back() != 8)
          bad_file(path, "field size " + printable(t) + " is not 1, 2, 4 or 8");
      }
    } else if (key == "TYPE") {
      ntype = vals.size();
      for (const auto& t : vals)
        if (t != "I" && t != "U" && t != "F") bad_file(path, "field type '" + printable(t) + "' is not I, U or F");
    } else if (key == "COUNT") {
      ncount = vals.size();
      for (const auto& t : vals) counts.push_back(number(t));
    } else if (key == "WIDTH" && vals.size() == 1) width = number(vals[0]), have_width = true;
    else if (key == "HEIGHT" && vals.size() == 1) height = number(vals[0]);
    else if (key == "POINTS" && vals.size() == 1) points = number(vals[0]), have_points = true;
    else if (key == "DATA" && vals.size() == 1) data = vals[0];
    else if (key != "VERSION" && key != "VIEWPOINT" && key != "WIDTH" && key != "HEIGHT" && key != "POINTS" &&
             key != "DATA")
      bad_file(path, "header line " + std::to_string(lines + 1) + " ('" + printable(line, 40) +
                         "') is not a PCD header field");
  }
  if (data.empty()) bad_file(path, "the header has no DATA line");
  // PCL's header loop does not stop at DATA: it goes on through the body's lines, skipping empty
  // ones and those whose first word starts with '#', and reads any whose first word begins with a
  // header keyword as a header line (a body starting with "COLUMNS" redefines the fields, and
  // PCL then reads past its arrays). It stops at the first other line; so does this check.
  const std::streampos body_start = in.tellg();
  for (std::string body; std::getline(in, body);) {
    if (body.empty()) continue;
    std::istringstream ls(body);
    std::string word;
    ls >> word;
    if (!word.empty() && word[0] == '#') continue;
    for (const char* key : kHeaderKeys)
      if (word.compare(0, std::strlen(key), key) == 0)
        bad_file(path, "the data after the DATA line starts with '" + std::string(key) +
                           "', which PCL would read as a header line");
    break;
  }
  in.clear();
  in.seekg(body_start);
  if (!nfields || nsize != nfields || ntype != nfields || (ncount && ncount != nfields))
    bad_file(path, "FIELDS, SIZE, TYPE and COUNT do not list the same number of fields");
  if (!have_width || !have_points || width * height != points)
    bad_file(path, "WIDTH x HEIGHT does not equal POINTS");
  for (std::size_t i = 0; i < nfields; ++i) point_bytes += sizes[i] * (ncount ? counts[i] : 1);
  // Counts below 2^32 and sizes below 16 keep point_bytes exact; the product may still wrap.
  std::size_t need = 0;
  if (__builtin_mul_overflow(points, point_bytes, &need))
    bad_file(path, std::to_string(points) + " points of " + std::to_string(point_bytes) + " bytes overflow a size");
  if (data == "ascii") return;
  if (data != "binary" && data != "binary_compressed") bad_file(path, "DATA '" + printable(data) + "' is not ascii, binary or binary_compressed");
  const std::streamoff body = static_cast<std::streamoff>(in.tellg());
  in.seekg(0, std::ios::end);
  const std::size_t left = static_cast<std::size_t>(static_cast<std::streamoff>(in.tellg()) - body);
  if (data == "binary") {
    if (left < need) bad_file(path, "truncated: " + std::to_string(points) + " points need " + std::to_string(need) +
                                     " bytes, the file has " + std::to_string(left));
    return;
  }
  std::uint32_t sz[2] = {0, 0};  // compressed and uncompressed sizes
  in.seekg(body);
  if (left < 8 || !in.read(reinterpret_cast<char*>(sz), 8)) bad_file(path, "truncated compressed data");
  if (sz[1] != need) bad_file(path, "compressed data does not hold POINTS points");
  if (left - 8 < sz[0]) bad_file(path, "truncated: compressed data needs " + std::to_string(sz[0]) + " bytes, the file has " +
                                           std::to_string(left - 8));
}


// PCL reads from a path. It is given a private in-memory copy of the checked bytes (a memfd,
// opened as /proc/self/fd/N), so it parses exactly what was checked: reading the path a second
// time would read whatever the file holds by then. Where memfd or /proc is missing, the path.
class CheckedCopy {
 public:
  CheckedCopy(const std::string& bytes, const std::string& path) : path_(path) {
    fd_ = ::memfd_create("occseg-pcd", MFD_CLOEXEC);
    if (fd_ < 0) return;
    for (std::size_t done = 0; done < bytes.size();) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw Error(Status::no_memory, "'" + path + "': no memory for a private copy of the file");
      done += static_cast<std::size_t>(n);
    }
    const std::string proc = "/proc/self/fd/" + std::to_string(fd_);
    if (::access(proc.c_str(), R_OK) == 0) path_ = proc;
  }
  ~CheckedCopy() {
    if (fd_ >= 0) ::close(fd_);
  }
  CheckedCopy(const CheckedCopy&) = delete;
  CheckedCopy& operator=(const CheckedCopy&) = delete;
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace

Grid read_pcd(const std::string& path, const ScanOptions& options) { return read_pcd(path, options, nullptr); }

Grid read_pcd(const std::string& path, const ScanOptions& options, PcdCloud* out) {
  options.validate();
  std::optional<CheckedCopy> copy;
  {
    const std::string bytes = read_file(path);
    check_header(path, bytes);
    copy.emplace(bytes, path);
  }  // the bytes are freed before PCL allocates its own
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  int version = 0;
  int rc = 0;
  try {
    pcl::PCDReader reader;
    rc = reader.read(copy->path(), blob, origin, orientation, version, 0);
  } catch (const pcl::PCLException& e) {
    bad_file(path, printable(e.detailedMessage(), 200));
  } catch (const std::bad_alloc&) {
    bad_file(path, "header claims more data than memory holds");
  } catch (const std::exception& e) {
    // PCL's header parser indexes its token vectors with at(): a malformed line that our header
    // check lets through surfaces as std::out_of_range (found by fuzz_pcd). It is the file's fault.
    bad_file(path, "PCL's reader rejected it: " + printable(e.what(), 200));
  }
  if (rc < 0) bad_file(path, "PCL's reader failed (code " + std::to_string(rc) + "; see its message above)");
  check_xyz_fields(path, blob);
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  if (out) {  // the file's fields and bytes, for writing it back with labels
    *out = PcdCloud();
    out->width = blob.width;
    out->height = blob.height;
    out->point_step = blob.point_step;
    for (const pcl::PCLPointField& f : blob.fields)
      out->fields.push_back({f.name, pcl::getFieldType(f.datatype), static_cast<unsigned>(pcl::getFieldSize(f.datatype)),
                             static_cast<unsigned>(f.count), f.offset});
    out->data = std::move(blob.data);
  }
  blob = pcl::PCLPointCloud2();  // free the raw copy before allocating the grid
  cloud.sensor_origin_ = origin;
  cloud.sensor_orientation_ = orientation;
  if (!origin.head<3>().allFinite() || !orientation.coeffs().allFinite() || orientation.norm() < 1e-6f)
    bad_file(path, "VIEWPOINT is not a finite pose");
  try {
    if (out) {
      out->viewpoint = {origin.x(), origin.y(), origin.z(), orientation.w(), orientation.x(), orientation.y(),
                        orientation.z()};
      out->pose = options.sensor_pose ? *options.sensor_pose : cloud_pose_d(cloud);
      out->xyz.resize(3 * cloud.size());
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        out->xyz[3 * i] = cloud[i].x;
        out->xyz[3 * i + 1] = cloud[i].y;
        out->xyz[3 * i + 2] = cloud[i].z;
      }
    }
    return integrate_cloud(cloud, options);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
}

std::vector<std::uint32_t> pcd_point_labels(const PcdCloud& cloud, const Grid& grid, const Result& result,
                                            int threads) {
  const std::size_t n = cloud.xyz.size() / 3;
  if (!(grid.dims == result.dims) || result.labels.size() != grid.dims.count())
    throw Error(Status::invalid_argument, "point labels: the result was not computed on this grid");
  GridFrame frame;
  frame.dims = grid.dims;
  frame.voxel_size = grid.voxel_size;
  frame.origin = grid.origin;
  std::vector<std::uint32_t> labels(n);
  const LabelArray& l = result.labels;
  scan_point_voxels(frame, cloud.pose, cloud.xyz.data(), n, 3, labels.data(),
                    [&l](std::uint64_t v) { return l[static_cast<std::size_t>(v)]; }, threads);
  return labels;
}

void write_points_pcd(const std::string& path, const PcdCloud& cloud, const std::vector<std::uint32_t>& labels,
                      StagedFiles* into) {
  const std::size_t n = cloud.width * cloud.height;
  if (labels.size() != n || cloud.data.size() < n * cloud.point_step)
    throw Error(Status::invalid_argument, "points.pcd: " + std::to_string(labels.size()) + " labels for " +
                                              std::to_string(n) + " points");
  std::vector<const PcdCloud::Field*> kept;  // every field but an old "label", then the new one
  std::size_t bytes = 4;
  for (const PcdCloud::Field& f : cloud.fields)
    if (f.name != "label") kept.push_back(&f), bytes += std::size_t(f.size) * f.count;
  std::ostringstream h;
  h.precision(9);  // the float VIEWPOINT, exactly
  h << "# .PCD v0.7 - Point Cloud Data file format (occseg: the input cloud, label = segment id, "
    << kNoPointLabel << " = none)\nVERSION 0.7\nFIELDS";
  for (const auto* f : kept) h << ' ' << f->name;
  h << " label\nSIZE";
  for (const auto* f : kept) h << ' ' << f->size;
  h << " 4\nTYPE";
  for (const auto* f : kept) h << ' ' << f->type;
  h << " U\nCOUNT";
  for (const auto* f : kept) h << ' ' << f->count;
  h << " 1\nWIDTH " << cloud.width << "\nHEIGHT " << cloud.height << "\nVIEWPOINT";
  for (double v : cloud.viewpoint) h << ' ' << v;
  h << "\nPOINTS " << n << "\nDATA binary\n";
  const std::string header = h.str();
  std::vector<char> body(n * bytes);
  for (std::size_t i = 0; i < n; ++i) {
    char* o = &body[i * bytes];
    const std::uint8_t* p = cloud.data.data() + i * cloud.point_step;
    for (const auto* f : kept) {
      const std::size_t len = std::size_t(f->size) * f->count;
      std::memcpy(o, p + f->offset, len);
      o += len;
    }
    std::memcpy(o, &labels[i], 4);
  }
  write_file_atomically(path, [&](std::ostream& os) {
    os.write(header.data(), static_cast<std::streamsize>(header.size()));
    os.write(body.data(), static_cast<std::streamsize>(body.size()));
  }, into);
}

void write_segments_pcd(const std::string& path, const Grid& grid, const Result& result, StateSet states,
                        StagedFiles* into) {
  const pcl::PointCloud<pcl::PointXYZL> cloud = labelled_cloud(grid, result, states);
  // Written by hand rather than with pcl::PCDWriter: PCL refuses empty clouds, and this goes
  // through write_file_atomically. Fields are packed (16 bytes a point), as DATA binary wants.
  std::ostringstream h;
  h << "# .PCD v0.7 - Point Cloud Data file format (occseg segments: label = segment id)\n"
    << "VERSION 0.7\nFIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
    << "WIDTH " << cloud.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << cloud.size()
    << "\nDATA binary\n";
  const std::string header = h.str();
  std::vector<char> body(cloud.size() * 16);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const pcl::PointXYZL& p = cloud[i];
    std::memcpy(&body[16 * i], &p.x, 4);
    std::memcpy(&body[16 * i + 4], &p.y, 4);
    std::memcpy(&body[16 * i + 8], &p.z, 4);
    std::memcpy(&body[16 * i + 12], &p.label, 4);
  }
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
  }, into);
}

}  // namespace occseg
