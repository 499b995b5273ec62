// The bad-input table of docs/reliability.md, C ABI rows: every bad value, dimension, stride,
// pointer and file gives its pinned status and a message naming the problem, and no handle.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "c_calls.h"
#include "support.hpp"

using namespace occseg::reliability;

namespace {

const std::size_t k444[3] = {4, 4, 4};

// occseg_map_from_buffer on 64 floats of 0.5 with one voxel replaced.
int import_with(float bad, std::uint32_t flags, occseg_map** m, std::size_t voxel = 21) {
  float p[64];
  for (float& v : p) v = 0.5f;
  p[voxel] = bad;
  return occseg_map_from_buffer_flags(m, p, OCCSEG_F32, k444, nullptr, 1.0, flags);
}

}  // namespace

TEST(BadValues, NanInfinitiesAndOutOfRangeProbabilitiesAreRefusedNamingTheVoxel) {
  occseg_map* m = reinterpret_cast<occseg_map*>(1);
  // Voxel 21 is (1, 1, 1) in x-fastest order.
  EXPECT_STATUS(import_with(NAN, 0, &m), OCCSEG_EVALUE, "voxel (1, 1, 1) = nan is NaN");
  EXPECT_EQ(m, nullptr);
  EXPECT_STATUS(import_with(INFINITY, 0, &m), OCCSEG_EVALUE, "= inf is infinite");
  EXPECT_STATUS(import_with(-INFINITY, 0, &m), OCCSEG_EVALUE, "= -inf is infinite");
  EXPECT_STATUS(import_with(-0.001f, 0, &m), OCCSEG_EVALUE, "is outside [0, 1]");
  EXPECT_STATUS(import_with(1.5f, 0, &m), OCCSEG_EVALUE, "= 1.5 is outside [0, 1]");
  EXPECT_EQ(m, nullptr);
  // F64 values that only a double holds (1 + 1e-12 rounds to 1.0f) are judged as doubles.
  double d[64];
  for (double& v : d) v = 0.5;
  d[63] = 1.0 + 1e-12;
  EXPECT_STATUS(occseg_map_from_buffer(&m, d, OCCSEG_F64, k444, nullptr, 1.0), OCCSEG_EVALUE,
                "voxel (3, 3, 3) = 1 is outside [0, 1]");
}

TEST(BadValues, FlagsTurnBadValuesIntoDefinedOnes) {
  occseg_map* m = nullptr;
  float v = -1;
  ASSERT_EQ(import_with(NAN, OCCSEG_IMPORT_NAN_UNKNOWN, &m), OCCSEG_OK);
  float out[64];
  ASSERT_EQ(occseg_map_values(m, out, 64), OCCSEG_OK);
  EXPECT_EQ(out[21], 0.5f);
  occseg_map_free(m);
  ASSERT_EQ(import_with(-INFINITY, OCCSEG_IMPORT_CLAMP, &m), OCCSEG_OK);
  ASSERT_EQ(occseg_map_values(m, out, 64), OCCSEG_OK);
  EXPECT_EQ(out[21], 0.0f);
  occseg_map_free(m);
  ASSERT_EQ(import_with(7.0f, OCCSEG_IMPORT_CLAMP, &m), OCCSEG_OK);
  ASSERT_EQ(occseg_map_values(m, &v, 1), OCCSEG_ERANGE);  // capacity 1 < 64 voxels: refused, untouched
  EXPECT_EQ(v, -1.0f);
  ASSERT_EQ(occseg_map_values(m, out, 64), OCCSEG_OK);
  EXPECT_EQ(out[21], 1.0f);
  occseg_map_free(m);
  // NaN is not clamped: only NAN_UNKNOWN accepts it.
  EXPECT_STATUS(import_with(NAN, OCCSEG_IMPORT_CLAMP, &m), OCCSEG_EVALUE, "is NaN");
}

TEST(BadValues, VoxelSizeAndOriginMustBeFinite) {
  float p[64] = {0};
  occseg_map* m = nullptr;
  for (double vs : {0.0, -1.0, double(NAN), double(INFINITY)})
    EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, nullptr, vs), OCCSEG_EVALUE, "voxel_size");
  ASSERT_EQ(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, nullptr, 1.0), OCCSEG_OK);
  EXPECT_STATUS(occseg_map_set_voxel_size(m, NAN), OCCSEG_EVALUE, "voxel_size nan");
  const double origin[3] = {0, INFINITY, 0};
  EXPECT_STATUS(occseg_map_set_origin(m, origin), OCCSEG_EVALUE, "origin[1] = inf is not finite");
  double vs = 0;
  ASSERT_EQ(occseg_map_voxel_size(m, &vs), OCCSEG_OK);
  EXPECT_EQ(vs, 1.0);  // a refused setter changes nothing
  occseg_map_free(m);
}

// A map whose box reaches beyond 2^40 voxels from the world origin, or whose far corner
// overflows to infinity, is refused where it would be made: before, occseg_map_write wrote such
// a map as an NRRD whose origin or extent its own reader refuses (or whose voxels all sat at one
// coordinate). Every map that is accepted writes and reads back with its geometry.
TEST(BadValues, MapsOutOfRangeAreRefusedSoEveryMapWrittenReadsBack) {
  float p[64];
  for (float& v : p) v = 0.25f;
  occseg_map* m = nullptr;
  // 4 voxels of 1e308 m: the far corner is inf.
  EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, nullptr, 1e308), OCCSEG_EVALUE, "out of range");
  EXPECT_EQ(m, nullptr);
  ASSERT_EQ(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, nullptr, 1.0), OCCSEG_OK);
  const double huge[3] = {1.7e308, 0, 0}, max[3] = {0, std::numeric_limits<double>::max(), 0};
  EXPECT_STATUS(occseg_map_set_origin(m, huge), OCCSEG_EVALUE, "out of range");
  EXPECT_STATUS(occseg_map_set_origin(m, max), OCCSEG_EVALUE, "out of range");
  const double beyond[3] = {0, 0, -std::ldexp(1.0, 40) - 8};  // 2^40 + 8 voxels from the origin
  EXPECT_STATUS(occseg_map_set_origin(m, beyond), OCCSEG_EVALUE, "extent in z");
  const double utm[3] = {500000.25, 5000000.5, 12.0};
  ASSERT_EQ(occseg_map_set_origin(m, utm), OCCSEG_OK);
  // A voxel size that puts the box out of range, with that origin, is refused too.
  EXPECT_STATUS(occseg_map_set_voxel_size(m, 1e-7), OCCSEG_EVALUE, "out of range");
  EXPECT_STATUS(occseg_map_set_voxel_size(m, 1e308), OCCSEG_EVALUE, "out of range");  // far corner inf
  double vs = 0, o[3] = {0, 0, 0};
  ASSERT_EQ(occseg_map_voxel_size(m, &vs), OCCSEG_OK);
  ASSERT_EQ(occseg_map_origin(m, o), OCCSEG_OK);
  EXPECT_EQ(vs, 1.0);  // refused setters change nothing
  EXPECT_EQ(o[0], utm[0]);
  EXPECT_EQ(o[1], utm[1]);
  // The edge of the range: 2^40 - 4 voxels of 2^-10 m from the world origin, written and read back.
  ASSERT_EQ(occseg_map_set_voxel_size(m, std::ldexp(1.0, -10)), OCCSEG_OK);
  const double edge[3] = {std::ldexp(1.0, 30) - 4 * std::ldexp(1.0, -10), -std::ldexp(1.0, 30), 0};
  ASSERT_EQ(occseg_map_set_origin(m, edge), OCCSEG_OK);
  const std::string dir = scratch("geometry");
  for (const char* name : {"edge.nrrd", "utm.nrrd"}) {
    if (std::string(name) == "utm.nrrd") {
      ASSERT_EQ(occseg_map_set_voxel_size(m, 0.05), OCCSEG_OK);
      ASSERT_EQ(occseg_map_set_origin(m, utm), OCCSEG_OK);
    }
    const std::string f = dir + "/" + name;
    ASSERT_EQ(occseg_map_write(m, f.c_str()), OCCSEG_OK) << occseg_last_error();
    occseg_map* back = nullptr;
    ASSERT_EQ(occseg_map_read(&back, f.c_str()), OCCSEG_OK) << name << ": " << occseg_last_error();
    double bvs = 0, bo[3] = {0, 0, 0};
    ASSERT_EQ(occseg_map_voxel_size(back, &bvs), OCCSEG_OK);
    ASSERT_EQ(occseg_map_origin(back, bo), OCCSEG_OK);
    ASSERT_EQ(occseg_map_voxel_size(m, &vs), OCCSEG_OK);
    ASSERT_EQ(occseg_map_origin(m, o), OCCSEG_OK);
    EXPECT_EQ(bvs, vs) << name;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(bo[k], o[k], 1e-9 * std::max(1.0, std::fabs(o[k]))) << name << " " << k;
    occseg_map_free(back);
  }
  occseg_map_free(m);
  // A hand-written NRRD whose origin is out of range is refused by the reader the same way.
  const std::string f = dir + "/far.nrrd";
  put(f, "NRRD0004\ntype: float\ndimension: 3\nspace: RAS\nsizes: 1 1 1\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n"
         "endian: little\nencoding: raw\nspace origin: (1.7e308,0,0)\n\n" + std::string(4, '\0'));
  EXPECT_STATUS(occseg_map_read(&m, f.c_str()), OCCSEG_EVALUE, "out of range");
  EXPECT_EQ(m, nullptr);
}

TEST(BadDims, ZeroHugeAndOverflowingDimensionsAreRefusedBeforeAnyRead) {
  const std::uint8_t one = 0;  // the data is never read: dims are checked first
  occseg_map* m = nullptr;
  const std::size_t zero[3] = {4, 0, 4};
  EXPECT_STATUS(occseg_map_from_buffer(&m, &one, OCCSEG_U8, zero, nullptr, 1.0), OCCSEG_EDIMS, "have a zero");
  const std::size_t beyond[3] = {std::size_t(1) << 21, std::size_t(1) << 20, 1};  // 2^41 voxels
  EXPECT_STATUS(occseg_map_from_buffer(&m, &one, OCCSEG_U8, beyond, nullptr, 1.0), OCCSEG_EDIMS,
                "exceed the limit of 2^40 voxels");
  // nx * ny * nz wraps around size_t to a small number: must not be taken for it.
  const std::size_t max = std::numeric_limits<std::size_t>::max();
  const std::size_t wraps[3] = {max / 2 + 1, 2, 3};  // product mod 2^64 == 2^64 / 2 * 2 * 3 mod 2^64 = 0
  EXPECT_STATUS(occseg_map_from_buffer(&m, &one, OCCSEG_U8, wraps, nullptr, 1.0), OCCSEG_EDIMS, "exceed");
  const std::size_t wraps_to_one[3] = {max, max, 1};  // max * max == 1 mod 2^64
  EXPECT_STATUS(occseg_map_from_buffer(&m, &one, OCCSEG_U8, wraps_to_one, nullptr, 1.0), OCCSEG_EDIMS, "exceed");
  EXPECT_EQ(m, nullptr);
}

TEST(BadStrides, OverlappingOverflowingAndNestedWronglyAreRefused) {
  float p[64] = {0};
  occseg_map* m = nullptr;
  const ptrdiff_t zero[3] = {4, 0, 64};  // every y row reads the same bytes
  EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, zero, 1.0), OCCSEG_EINVAL,
                "strides[1] = 0 makes voxels overlap");
  const ptrdiff_t partial[3] = {4, 8, 64};  // y steps over half an x row
  EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, partial, 1.0), OCCSEG_EINVAL, "overlap");
  const ptrdiff_t small[3] = {2, 16, 64};  // 4-byte floats 2 bytes apart
  EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, small, 1.0), OCCSEG_EINVAL, "strides[0] = 2");
  const ptrdiff_t neg_overlap[3] = {-4, -8, 64};
  EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, neg_overlap, 1.0), OCCSEG_EINVAL, "overlap");
  const ptrdiff_t pmin[3] = {4, 16, std::numeric_limits<ptrdiff_t>::min()};
  EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, pmin, 1.0), OCCSEG_EINVAL, "overflows");
  const ptrdiff_t huge[3] = {4, 16, std::numeric_limits<ptrdiff_t>::max() / 2};  // 3 steps pass 2^63
  EXPECT_STATUS(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, huge, 1.0), OCCSEG_EINVAL,
                "span more bytes than an address can hold");
  EXPECT_EQ(m, nullptr);
}

TEST(BadStrides, NegativeStridesReadTheFlippedView) {
  // Voxel (x, y, z) stored at (3 - x) + 4 * (y + 4 * (3 - z)); data points at voxel (0, 0, 0).
  float p[64];
  for (int i = 0; i < 64; ++i) p[i] = float(i) / 64.0f;
  const ptrdiff_t s[3] = {-4, 16, -64};
  occseg_map* m = nullptr;
  ASSERT_EQ(occseg_map_from_buffer(&m, p + 3 + 4 * 4 * 3, OCCSEG_F32, k444, s, 1.0), OCCSEG_OK);
  float out[64];
  ASSERT_EQ(occseg_map_values(m, out, 64), OCCSEG_OK);
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) EXPECT_EQ(out[x + 4 * (y + 4 * z)], p[(3 - x) + 4 * (y + 4 * (3 - z))]);
  occseg_map_free(m);
}

TEST(BadEnums, DtypeFlagsPresetAndParameterValuesAreRefused) {
  float p[64] = {0};
  occseg_map* m = nullptr;
  EXPECT_STATUS(occseg_test_from_buffer(&m, p, 9, k444, nullptr, 1.0, 0), OCCSEG_EINVAL,
                "dtype 9 is not an occseg_dtype");
  EXPECT_STATUS(occseg_test_from_buffer(&m, p, -1, k444, nullptr, 1.0, 0), OCCSEG_EINVAL, "dtype -1");
  EXPECT_STATUS(occseg_map_from_buffer_flags(&m, p, OCCSEG_F32, k444, nullptr, 1.0, 8), OCCSEG_EINVAL, "flags 8");
  // Stage kinds beyond the enumerators: nothing there, no crash.
  EXPECT_EQ(occseg_test_stage_count(4), 0u);
  EXPECT_EQ(occseg_test_stage_count(-1), 0u);
  EXPECT_EQ(occseg_test_stage_name(9, 0), nullptr);
  EXPECT_GT(occseg_test_stage_count(0), 0u);
  occseg_params* params = nullptr;
  ASSERT_EQ(occseg_params_create(&params), OCCSEG_OK);
  EXPECT_STATUS(occseg_params_set(params, "preset", "fast"), OCCSEG_EINVAL, "fast");
  EXPECT_STATUS(occseg_params_set(params, "smax", "-3"), OCCSEG_EINVAL, "smax");
  EXPECT_STATUS(occseg_params_set(params, "smax", "nan"), OCCSEG_EINVAL, "smax");
  EXPECT_STATUS(occseg_params_set_double(params, "split_ratio", INFINITY), OCCSEG_EINVAL, "split_ratio");
  EXPECT_STATUS(occseg_params_set(params, "no_such_parameter", "1"), OCCSEG_EINVAL, "no_such_parameter");
  EXPECT_STATUS(occseg_params_set_int(params, "threads", -1), OCCSEG_EINVAL, "threads");
  // Individually valid, together inconsistent: refused by occseg_segment too.
  ASSERT_EQ(occseg_params_set_int(params, "smin", 64), OCCSEG_OK);
  ASSERT_EQ(occseg_params_set_int(params, "smax", 8), OCCSEG_OK);
  ASSERT_EQ(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, nullptr, 1.0), OCCSEG_OK);
  occseg_result* r = reinterpret_cast<occseg_result*>(1);
  EXPECT_STATUS(occseg_segment(&r, m, params), OCCSEG_EINVAL, "smin");
  EXPECT_EQ(r, nullptr);
  occseg_map_free(m);
  occseg_params_free(params);
}

TEST(NullPointers, EveryPointerArgumentIsCheckedAndNamed) {
  float p[64] = {0};
  occseg_map* m = nullptr;
  ASSERT_EQ(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, nullptr, 1.0), OCCSEG_OK);
  occseg_params* params = nullptr;
  ASSERT_EQ(occseg_params_create(&params), OCCSEG_OK);
  occseg_result* r = nullptr;
  ASSERT_EQ(occseg_segment(&r, m, params), OCCSEG_OK);
  occseg_map* mo = nullptr;
  occseg_result* ro = nullptr;
  std::size_t dims[3];
  double d = 0, o3[3];
  std::int64_t i64 = 0;
  std::uint32_t labels[64], u = 0;
  std::uint8_t states[64];
  float values[64];
  char buf[32];
  const char* stage = nullptr;
  occseg_segment_info info;
  info.struct_size = sizeof info;
  const char* const kNull = "is NULL";
  // map
  EXPECT_STATUS(occseg_map_from_buffer(nullptr, p, OCCSEG_F32, k444, nullptr, 1.0), OCCSEG_EINVAL, "'out' is NULL");
  EXPECT_STATUS(occseg_map_from_buffer(&mo, nullptr, OCCSEG_F32, k444, nullptr, 1.0), OCCSEG_EINVAL, "'data' is NULL");
  EXPECT_STATUS(occseg_map_from_buffer(&mo, p, OCCSEG_F32, nullptr, nullptr, 1.0), OCCSEG_EINVAL, "'dims' is NULL");
  EXPECT_STATUS(occseg_map_read(nullptr, "x.npy"), OCCSEG_EINVAL, "'out' is NULL");
  EXPECT_STATUS(occseg_map_read(&mo, nullptr), OCCSEG_EINVAL, "'path' is NULL");
  EXPECT_STATUS(occseg_map_write(nullptr, "x.npy"), OCCSEG_EINVAL, "'map' is NULL");
  EXPECT_STATUS(occseg_map_write(m, nullptr), OCCSEG_EINVAL, "'path' is NULL");
  EXPECT_STATUS(occseg_map_dims(nullptr, dims), OCCSEG_EINVAL, "'map' is NULL");
  EXPECT_STATUS(occseg_map_dims(m, nullptr), OCCSEG_EINVAL, "'dims' is NULL");
  EXPECT_STATUS(occseg_map_voxel_size(nullptr, &d), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_voxel_size(m, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_set_voxel_size(nullptr, 1.0), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_origin(nullptr, o3), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_origin(m, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_set_origin(nullptr, o3), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_set_origin(m, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_values(nullptr, values, 64), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_map_values(m, nullptr, 64), OCCSEG_EINVAL, kNull);
  // params
  EXPECT_STATUS(occseg_params_create(nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_copy(nullptr, params), OCCSEG_EINVAL, kNull);
  occseg_params* pc = nullptr;
  EXPECT_STATUS(occseg_params_copy(&pc, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_preset(nullptr, "paper"), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_preset(params, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_set(nullptr, "smax", "8"), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_set(params, nullptr, "8"), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_set(params, "smax", nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_set_int(nullptr, "smax", 8), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_set_double(params, nullptr, 8), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_set_string(params, "preset", nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_get_int(params, "smax", nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_get_int(nullptr, "smax", &i64), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_get_double(params, nullptr, &d), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_get(nullptr, "smax", buf, sizeof buf, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_get_string(params, nullptr, buf, sizeof buf, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_validate(nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_params_set_progress(nullptr, nullptr, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_param_find(nullptr, &u), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_param_find("smax", nullptr), OCCSEG_EINVAL, kNull);
  // segment and result
  EXPECT_STATUS(occseg_segment(nullptr, m, params), OCCSEG_EINVAL, "'out' is NULL");
  EXPECT_STATUS(occseg_segment(&ro, nullptr, params), OCCSEG_EINVAL, "'map' is NULL");
  EXPECT_STATUS(occseg_result_dims(nullptr, dims), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_result_dims(r, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_EQ(occseg_result_segment_count(nullptr), 0u);
  EXPECT_NE(std::string(occseg_last_error()).find(kNull), std::string::npos);
  EXPECT_STATUS(occseg_result_segment(nullptr, 0, &info), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_result_segment(r, 0, nullptr), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_result_labels(nullptr, labels, 64), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_result_labels(r, nullptr, 64), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_result_states(nullptr, states, 64), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_result_states(r, nullptr, 64), OCCSEG_EINVAL, kNull);
  EXPECT_EQ(occseg_result_stage_count(nullptr), 0u);
  EXPECT_STATUS(occseg_result_stage(nullptr, 0, &stage, &d), OCCSEG_EINVAL, kNull);
  EXPECT_STATUS(occseg_result_write(nullptr, "dir"), OCCSEG_EINVAL, "'result' is NULL");
  EXPECT_STATUS(occseg_result_write(r, nullptr), OCCSEG_EINVAL, "'dir' is NULL");
  // NULL is fine where documented: params of occseg_segment, stage outputs, every *_free.
  occseg_result* r2 = nullptr;
  EXPECT_EQ(occseg_segment(&r2, m, nullptr), OCCSEG_OK);
  EXPECT_EQ(occseg_result_stage(r, 0, nullptr, nullptr), OCCSEG_OK);
  EXPECT_EQ(mo, nullptr);
  EXPECT_EQ(ro, nullptr);
  occseg_map_free(nullptr);
  occseg_params_free(nullptr);
  occseg_result_free(nullptr);
  occseg_result_free(r2);
  occseg_result_free(r);
  occseg_params_free(params);
  occseg_map_free(m);
}

TEST(BadResultQueries, IndicesCapacitiesAndStructSizesAreChecked) {
  const std::vector<float> p = box_map(8);
  const std::size_t d8[3] = {8, 8, 8};
  occseg_map* m = nullptr;
  ASSERT_EQ(occseg_map_from_buffer(&m, p.data(), OCCSEG_F32, d8, nullptr, 1.0), OCCSEG_OK);
  occseg_result* r = nullptr;
  ASSERT_EQ(occseg_segment(&r, m, nullptr), OCCSEG_OK);
  std::vector<std::uint32_t> labels(511, 7u);
  EXPECT_STATUS(occseg_result_labels(r, labels.data(), labels.size()), OCCSEG_ERANGE, "count 511 is smaller than the 512");
  EXPECT_EQ(labels[0], 7u);  // untouched
  occseg_segment_info info;
  info.struct_size = sizeof info;
  const std::uint32_t n = occseg_result_segment_count(r);
  EXPECT_STATUS(occseg_result_segment(r, n, &info), OCCSEG_ERANGE, "out of range");
  info.struct_size = 3;
  EXPECT_STATUS(occseg_result_segment(r, 0, &info), OCCSEG_EINVAL, "struct_size 3");
  const char* stage = nullptr;
  EXPECT_STATUS(occseg_result_stage(r, 99, &stage, nullptr), OCCSEG_ERANGE, "99");
  occseg_result_free(r);
  occseg_map_free(m);
}
