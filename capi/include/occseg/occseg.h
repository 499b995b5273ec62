/*
 * occseg.h: the stable C ABI of occseg, texture-based segmentation of 3D probabilistic
 * occupancy maps.
 *
 * One header, opaque handles, plain C99. Link with `pkg-config --cflags --libs occseg` or, from
 * CMake, `find_package(occseg)` and `target_link_libraries(app PRIVATE occseg::occseg)`.
 *
 * Conventions
 *   - Functions returning `int` return 0 (OCCSEG_OK) on success and a negative OCCSEG_E* code
 *     on failure. Every failure also sets a message for occseg_last_error() naming the function,
 *     the argument and the offending value; a success clears it.
 *   - Output handles (`occseg_map **out`, ...) are set to NULL on failure, so freeing them
 *     unconditionally is always safe. Every *_free function accepts NULL.
 *   - No C++ exception, no `bool`, no variadic function and no STL type crosses this ABI.
 *     Everything that is a macro here (version numbers) is also reachable through a function,
 *     for foreign-function interfaces that cannot see macros.
 *   - Structs the library fills (occseg_segment_info) begin with `struct_size`, which the caller
 *     sets to sizeof(the struct) so later versions can append fields without breaking old callers.
 *
 * Thread safety
 *   - All functions are reentrant. Distinct handles may be used from distinct threads at the
 *     same time; one map or one result may be read (segmented, queried) by several threads at
 *     once, as long as no thread modifies it (occseg_map_set_*) meanwhile.
 *   - An occseg_params object must not be modified (occseg_params_set*, _preset, _set_progress)
 *     while another thread reads it or passes it to occseg_segment(). occseg_segment() copies
 *     the parameters at its start, so the object may be changed or freed once it has returned.
 *   - occseg_last_error() is per thread: it describes the last failing call of the calling thread.
 *   - The progress callback is called on the thread that called occseg_segment().
 *   - A map made by occseg_map_view_buffer reads the caller's buffer during every call on it: the
 *     buffer must stay alive and must not be written while any call uses the map (see there).
 *   - No handle may be freed (or a result recycled) while a call uses it: not from another
 *     thread, and not from inside the progress callback of an occseg_segment() or
 *     occseg_context_segment() that uses that map or context; the call would read freed memory.
 *   - Threads writing the same path at once (occseg_map_write, occseg_result_write) each write
 *     a complete file, never a mixture, but which one remains is unspecified, and the two files
 *     of occseg_result_write may then come from different results.
 */
#ifndef OCCSEG_OCCSEG_H
#define OCCSEG_OCCSEG_H

#include <stddef.h>
#include <stdint.h>

#include "occseg/occseg_version.h"

/* OCCSEG_API marks every exported function; the library is built with hidden visibility. */
#if defined(_WIN32) || defined(__CYGWIN__)
#  if defined(OCCSEG_BUILDING_LIBRARY)
#    define OCCSEG_API __declspec(dllexport)
#  else
#    define OCCSEG_API __declspec(dllimport)
#  endif
#elif defined(__GNUC__) && __GNUC__ >= 4
#  define OCCSEG_API __attribute__((visibility("default")))
#else
#  define OCCSEG_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ========================================================================================== */
/*  Version                                                                                   */
/* ========================================================================================== */

/* OCCSEG_VERSION_NUMBER of the library actually loaded (major * 10000 + minor * 100 + patch),
 * which may differ from the header the caller was compiled with. */
OCCSEG_API uint32_t occseg_version_number(void);

/* "MAJOR.MINOR.PATCH" of the library actually loaded. Static storage, never NULL. */
OCCSEG_API const char *occseg_version_string(void);

/* ========================================================================================== */
/*  Errors                                                                                    */
/* ========================================================================================== */

/* Status codes. The values are pinned: they never change between versions. */
typedef enum {
  OCCSEG_OK = 0,
  OCCSEG_EINVAL = -1,       /* NULL pointer, bad enum, bad stride, bad parameter name or value */
  OCCSEG_EDIMS = -2,        /* zero, overflowing or too-large dimensions (limit 2^40 voxels) */
  OCCSEG_EVALUE = -3,       /* NaN, infinity or probability outside [0, 1]; bad voxel size */
  OCCSEG_ENOMEM = -4,       /* allocation failed */
  OCCSEG_EIO = -5,          /* file cannot be opened, read or written */
  OCCSEG_EFORMAT = -6,      /* file is truncated, corrupt or not of the expected format */
  OCCSEG_ERANGE = -7,       /* index out of range, output buffer too small */
  OCCSEG_ECANCELLED = -8,   /* the progress callback asked to stop */
  OCCSEG_EPLUGIN = -9,      /* plugin failed to load or register */
  OCCSEG_EUNSUPPORTED = -10,/* valid request this build cannot serve */
  OCCSEG_EINTERNAL = -11    /* a bug: please report it with the occseg_last_error() text */
} occseg_status;

/* Short description of a status code ("invalid argument", ...). Static storage, never NULL;
 * "unknown status" for codes that are not an occseg_status. */
OCCSEG_API const char *occseg_status_string(int code);

/* Symbolic name of a status code ("OCCSEG_EINVAL", ...). Static storage, never NULL;
 * "OCCSEG_E?" for codes that are not an occseg_status. */
OCCSEG_API const char *occseg_status_name(int code);

/* Detail of the calling thread's last failure ("" when the last call succeeded or nothing has
 * failed yet). Never NULL; valid until the thread's next occseg call. */
OCCSEG_API const char *occseg_last_error(void);

/* ========================================================================================== */
/*  Parameters                                                                                */
/* ========================================================================================== */

/* Every setting of the pipeline, by name. Created with the "default" preset. */
typedef struct occseg_params occseg_params;

/* Progress callback: `stage` is "texture", "division", "creation", "refinement" or "labelling",
 * `fraction` in [0, 1]. Return 0 to go on, nonzero to cancel: occseg_segment() then returns
 * OCCSEG_ECANCELLED and produces no result. */
typedef int (*occseg_progress_fn)(const char *stage, double fraction, void *user);

/* Creates a parameter set holding the "default" preset. */
OCCSEG_API int occseg_params_create(occseg_params **out);

/* Creates an independent copy of `src` (values and progress callback). */
OCCSEG_API int occseg_params_copy(occseg_params **out, const occseg_params *src);

/* Frees a parameter set. NULL is a no-op. */
OCCSEG_API void occseg_params_free(occseg_params *params);

/* Resets every value to a preset: "paper" (as published) or "default" (paper plus per-voxel
 * safety rules). Keeps the progress callback. Same as occseg_params_set(p, "preset", name). */
OCCSEG_API int occseg_params_preset(occseg_params *params, const char *name);

/* Sets any parameter from text ("smax", "64"). Unknown names, unparsable text and values outside
 * the parameter's bounds fail with OCCSEG_EINVAL and leave the value unchanged. */
OCCSEG_API int occseg_params_set(occseg_params *params, const char *name, const char *value);

/* Typed setters. _int works for "int" and "double" parameters, _double for "double" and (when
 * the value is integral) "int" parameters, _string for "string" parameters only. */
OCCSEG_API int occseg_params_set_int(occseg_params *params, const char *name, int64_t value);
OCCSEG_API int occseg_params_set_double(occseg_params *params, const char *name, double value);
OCCSEG_API int occseg_params_set_string(occseg_params *params, const char *name, const char *value);

/* Typed getters. _int reads "int" parameters, _double "int" and "double" ones. */
OCCSEG_API int occseg_params_get_int(const occseg_params *params, const char *name, int64_t *out);
OCCSEG_API int occseg_params_get_double(const occseg_params *params, const char *name, double *out);

/* Text getters, snprintf-like: `*length` (if not NULL) receives the text's length without the
 * terminating NUL. With buf == NULL and size == 0 only the length is returned. A buffer smaller
 * than length + 1 fails with OCCSEG_ERANGE and is left untouched. _get_string reads "string"
 * parameters only; occseg_params_get reads any parameter as the text occseg_params_set accepts. */
OCCSEG_API int occseg_params_get_string(const occseg_params *params, const char *name, char *buf,
                                        size_t size, size_t *length);
OCCSEG_API int occseg_params_get(const occseg_params *params, const char *name, char *buf,
                                 size_t size, size_t *length);

/* Installs (or, with fn == NULL, removes) the progress callback used by occseg_segment(). */
OCCSEG_API int occseg_params_set_progress(occseg_params *params, occseg_progress_fn fn, void *user);

/* Checks the combination of values (smin <= smax, powers of two, free_below <= occupied_above),
 * which the single setters cannot; occseg_segment() performs the same check. */
OCCSEG_API int occseg_params_validate(const occseg_params *params);

/* The table of parameters: names, kinds ("int", "double", "string"), bounds and one-line
 * descriptions, for building user interfaces. Indices run from 0 to occseg_param_count() - 1;
 * the strings have static storage. Past the end, the string functions return NULL. */
OCCSEG_API uint32_t occseg_param_count(void);
OCCSEG_API const char *occseg_param_name(uint32_t index);
OCCSEG_API const char *occseg_param_kind(uint32_t index);
OCCSEG_API const char *occseg_param_description(uint32_t index);
/* Inclusive bounds of a numeric parameter (both 0 for "string" parameters). */
OCCSEG_API int occseg_param_bounds(uint32_t index, double *min, double *max);
/* Index of a parameter by name; OCCSEG_EINVAL for unknown names. */
OCCSEG_API int occseg_param_find(const char *name, uint32_t *index);

/* ========================================================================================== */
/*  Maps                                                                                      */
/* ========================================================================================== */

/* A probabilistic occupancy grid: nx * ny * nz occupancy probabilities in [0, 1], a voxel edge
 * length and the world position of the outer corner of voxel (0, 0, 0). */
typedef struct occseg_map occseg_map;

/* Element type of a caller's buffer. U8 and U16 map 0..max onto 0..1. I8_OCCUPANCY is the int8
 * cell of a ROS nav_msgs/OccupancyGrid (and of a map_server map once loaded): -1 is unknown
 * (p = 0.5), 0..100 is the occupancy in percent (p = v / 100); any other value fails with
 * OCCSEG_EVALUE naming the first such cell. An OccupancyGrid's `data` is row-major with x
 * fastest and row 0 at the grid's origin, which is occseg's own layout: pass it as it is, with
 * dims {width, height, 1}, voxel_size = info.resolution and the origin's position (a map whose
 * origin is rotated about z is not an axis-aligned grid). The values are pinned. */
typedef enum {
  OCCSEG_F32 = 0,
  OCCSEG_F64 = 1,
  OCCSEG_U8 = 2,
  OCCSEG_U16 = 3,
  OCCSEG_I8_OCCUPANCY = 4
} occseg_dtype;

/* Flags of occseg_map_from_buffer_flags (bitwise or). */
typedef enum {
  OCCSEG_IMPORT_STRICT = 0,      /* F32/F64 values outside [0, 1], infinities and NaN fail */
  OCCSEG_IMPORT_CLAMP = 1,       /* values below 0 (and -inf) become 0, above 1 (and +inf) 1 */
  OCCSEG_IMPORT_NAN_UNKNOWN = 2, /* NaN becomes 0.5, i.e. unknown */
  OCCSEG_IMPORT_BYTE_SWAPPED = 4 /* the items (F32, F64, U16) are stored in the byte order opposite
                                    to the machine's (big-endian data on x86): each is byte-swapped
                                    as it is read, then converted as a native one would be */
} occseg_import_flags;

/* Copies a caller's 3D array into a new map. Voxel (x, y, z) is read at
 *   (const char *)data + x * strides[0] + y * strides[1] + z * strides[2]
 * with strides in bytes (any alignment, negative strides allowed: `data` then points at voxel
 * (0, 0, 0), not at the lowest address). strides == NULL means dense with x fastest. Strides
 * that make two voxels overlap (e.g. 0 along an axis of more than one voxel) or whose extent
 * overflows fail with OCCSEG_EINVAL; axes ordered by |stride| must nest, as in every view
 * NumPy can produce. Zero or overflowing dims (more than 2^40 voxels) fail with OCCSEG_EDIMS.
 * F32/F64 values must be probabilities in [0, 1]: the first voxel (x fastest) that is NaN,
 * infinite or out of range fails with OCCSEG_EVALUE naming it; likewise an I8_OCCUPANCY cell
 * outside -1..100 (the flags do not apply to it). voxel_size must be positive and
 * finite (OCCSEG_EVALUE). The origin starts at (0, 0, 0). A map's box must lie within 2^40
 * voxels of the world origin, corners origin and origin + dims * voxel_size alike (beyond,
 * voxel corners would round together or overflow to infinity): here, in the setters below and
 * for every map read, OCCSEG_EVALUE "out of range" otherwise, so every map can be written. */
OCCSEG_API int occseg_map_from_buffer(occseg_map **out, const void *data, occseg_dtype dtype,
                                      const size_t dims[3] /* nx, ny, nz */,
                                      const ptrdiff_t strides[3] /* bytes; NULL: dense, x fastest */,
                                      double voxel_size);

/* As occseg_map_from_buffer, with occseg_import_flags to clamp or accept bad F32/F64 values. */
OCCSEG_API int occseg_map_from_buffer_flags(occseg_map **out, const void *data, occseg_dtype dtype,
                                            const size_t dims[3], const ptrdiff_t strides[3],
                                            double voxel_size, uint32_t flags);

/* Reads a map with the reader registered for the path's extension (see Plugins below): .npy
 * (float32, float64, uint8 or uint16, indexed [z, y, x] or [y, x], C or Fortran order; voxel
 * size 1, origin (0, 0, 0)), .nrrd (origin and voxel size in the file's own space, e.g. LPS,
 * which the map remembers for occseg_map_write), .yaml (a ROS map_server / Nav2 2D map: the PGM
 * image it names, its resolution and origin; cells as map_server makes them, then p as for
 * OCCSEG_I8_OCCUPANCY; an origin yaw other than 0 fails with OCCSEG_EUNSUPPORTED), or what
 * plugins add. OCCSEG_EIO if it cannot be read or is not a regular file (a FIFO, a device:
 * refused before any read, so nothing blocks), OCCSEG_EFORMAT if it is not a valid file,
 * OCCSEG_EVALUE for bad probabilities or a box out of range, OCCSEG_EUNSUPPORTED for an
 * extension no reader handles. */
OCCSEG_API int occseg_map_read(occseg_map **out, const char *path);

/* Writes the map with the writer registered for the path's extension: .npy (float32 [z, y, x]),
 * .nrrd (float, with voxel size and origin, in the space of the .nrrd the map was read from, else
 * right-anterior-superior), or what plugins add; all or nothing: the built-in writers write a new
 * temporary beside `path` completely (created as occseg_result_write's are) and rename it over
 * `path` only then, so on any failure (OCCSEG_EIO naming the path) the old file is unchanged and
 * no temporary is left. OCCSEG_EUNSUPPORTED for an extension no writer handles. */
OCCSEG_API int occseg_map_write(const occseg_map *map, const char *path);

/* Frees a map. NULL is a no-op. */
OCCSEG_API void occseg_map_free(occseg_map *map);

/* Dimensions nx, ny, nz. */
OCCSEG_API int occseg_map_dims(const occseg_map *map, size_t dims[3]);

/* Edge length of a voxel in metres (positive and finite; the box stays within range, see above). */
OCCSEG_API int occseg_map_voxel_size(const occseg_map *map, double *out);
OCCSEG_API int occseg_map_set_voxel_size(occseg_map *map, double voxel_size);

/* World position of the outer corner of voxel (0, 0, 0) (finite; the box stays within range). */
OCCSEG_API int occseg_map_origin(const occseg_map *map, double origin[3]);
OCCSEG_API int occseg_map_set_origin(occseg_map *map, const double origin[3]);

/* Copies the nx * ny * nz probabilities, x fastest, as stored (float). `count` is the capacity
 * of `out` in elements; less than nx * ny * nz fails with OCCSEG_ERANGE. */
OCCSEG_API int occseg_map_values(const occseg_map *map, float *out, size_t count);

/* ========================================================================================== */
/*  Segmentation                                                                              */
/* ========================================================================================== */

/* The output of occseg_segment(): a segment id per voxel and the segment table. */
typedef struct occseg_result occseg_result;

/* Voxel and segment states. */
typedef enum { OCCSEG_FREE = 0, OCCSEG_UNKNOWN = 1, OCCSEG_OCCUPIED = 2 } occseg_state;

/* Runs the whole pipeline (texture, division, creation, refinement, labelling) on a map.
 * params == NULL uses the "default" preset. The map and the parameters are only read. Fails
 * with OCCSEG_EINVAL for an inconsistent parameter set, OCCSEG_ECANCELLED when the progress
 * callback cancels, OCCSEG_ENOMEM when memory runs out. */
OCCSEG_API int occseg_segment(occseg_result **out, const occseg_map *map, const occseg_params *params);

/* A caller-owned context: a small pool of worker threads kept between calls, and (with
 * occseg_context_recycle) the label array of a result handed back. occseg_segment() itself runs
 * on a pool leased from a few idle pools the library keeps for the process (one call per pool at
 * a time: concurrent calls never wait for each other; abandoned in a fork()ed child, joined at
 * exit); nothing else is kept between its calls. A program that segments maps again and again (a
 * robot re-segmenting its map at a few hertz) may also run them on a context of its own, which
 * can recycle results. Contexts are independent of each other. */
typedef struct occseg_context occseg_context;

/* Starts a context with `threads` threads in all (the calling thread included; 0: one per
 * core). Fails with OCCSEG_EINVAL for a count outside [0, 1024]. If the system refuses a
 * thread, the pool is simply smaller. */
OCCSEG_API int occseg_context_new(occseg_context **out, int threads);

/* Stops the context's threads and frees it. NULL is a no-op. Must not be called while another
 * thread is inside occseg_context_segment() with the same context. */
OCCSEG_API void occseg_context_free(occseg_context *context);

/* Threads the context runs a call on (the calling thread included); 0 for NULL. */
OCCSEG_API int occseg_context_threads(const occseg_context *context);

/* occseg_segment() with its parallel stages on the context's threads, at most the parameter
 * "threads" of them (0: all). The result is identical to occseg_segment()'s. One call at a time
 * per context: calls from several threads on one context wait for each other. The progress
 * callback is called on the calling thread. */
OCCSEG_API int occseg_context_segment(occseg_result **out, occseg_context *context, const occseg_map *map,
                                      const occseg_params *params);

/* Frees `result` as occseg_result_free() does, but keeps its label array in `context`: the next
 * occseg_context_segment() on the context writes its labels there instead of allocating and
 * paging in 4 bytes per voxel of fresh memory, whose pages the system zeroes (about 8 % of a call
 * on a 320 x 320 x 128 map). The context keeps one array, the last one handed back, until a call
 * takes it (a map with more voxels than it holds gets fresh memory) or occseg_context_free():
 * 4 bytes per voxel held between calls, a trade the caller makes per result. The call that takes
 * it uses it for its scratch and its labels: its peak memory is that of a plain call.
 * A NULL context just frees the result; a NULL result is a no-op. Accessors must not be used on
 * `result` afterwards. */
OCCSEG_API void occseg_context_recycle(occseg_context *context, occseg_result *result);

/* ========================================================================================== */
/*  Results                                                                                   */
/* ========================================================================================== */

/* What a segment is in the scene (docs/algorithm.md, default preset rule 9). The values are
 * pinned: free and unknown follow the state; an occupied segment is structure (it lies mostly on
 * a support plane: a floor, a wall, a table top), an object, or clutter (fewer than
 * min_object_voxels voxels). The paper preset has only free, unknown and object. */
typedef enum {
  OCCSEG_KIND_FREE = 0,
  OCCSEG_KIND_UNKNOWN = 1,
  OCCSEG_KIND_STRUCTURE = 2,
  OCCSEG_KIND_OBJECT = 3,
  OCCSEG_KIND_CLUTTER = 4
} occseg_kind;

/* sizeof(occseg_segment_info) of the headers before `kind` was appended (occseg 0.x up to the
 * version that added it): occseg_result_segment() still accepts it and fills only the fields up
 * to `centroid`. */
#define OCCSEG_SEGMENT_INFO_SIZE_V1 80u

/* One segment: a region of voxels of one state (6-connected; in the default preset occupied
 * voxels 26-connected and joined across gaps of unknown voxels, small regions joined to their
 * neighbours, and an occupied region may be split into the support plane and the objects
 * standing on it; docs/algorithm.md). New fields are only ever appended. */
typedef struct {
  uint32_t struct_size;   /* set by the caller to sizeof(occseg_segment_info) */
  uint32_t id;            /* equals its index in the table and its label in the label array */
  occseg_state state;
  uint64_t voxels;        /* number of voxels */
  double mop;             /* mean occupancy probability of its voxels */
  uint32_t bbox_min[3], bbox_max[3];  /* voxel indices (x, y, z), both inclusive */
  double centroid[3];     /* mean voxel index (x, y, z) */
  occseg_kind kind;       /* appended: filled when struct_size is sizeof(occseg_segment_info) */
} occseg_segment_info;

/* Frees a result. NULL is a no-op. */
OCCSEG_API void occseg_result_free(occseg_result *result);

/* Dimensions nx, ny, nz of the segmented map. */
OCCSEG_API int occseg_result_dims(const occseg_result *result, size_t dims[3]);

/* Number of segments (0 for a NULL result, which also sets occseg_last_error()). */
OCCSEG_API uint32_t occseg_result_segment_count(const occseg_result *result);

/* Fills `*out` with segment `index` (0 .. count - 1; OCCSEG_ERANGE beyond). out->struct_size
 * must be set to sizeof(occseg_segment_info) of a version of this header: this one's, or
 * OCCSEG_SEGMENT_INFO_SIZE_V1 (a caller compiled before `kind`: the fields up to `centroid` are
 * filled and nothing beyond them is written); any other value fails with OCCSEG_EINVAL. */
OCCSEG_API int occseg_result_segment(const occseg_result *result, uint32_t index,
                                     occseg_segment_info *out);

/* Copies nx * ny * nz labels (segment ids), x fastest. `count` is the capacity of `out` in
 * elements; less than nx * ny * nz fails with OCCSEG_ERANGE. */
OCCSEG_API int occseg_result_labels(const occseg_result *result, uint32_t *out, size_t count);

/* Copies nx * ny * nz voxel states (occseg_state values), x fastest; `count` as above. */
OCCSEG_API int occseg_result_states(const occseg_result *result, uint8_t *out, size_t count);

/* Wall-clock time of each pipeline stage, in order. `*stage` points into the result and lives
 * as long as it. Either output pointer may be NULL. */
OCCSEG_API uint32_t occseg_result_stage_count(const occseg_result *result);
OCCSEG_API int occseg_result_stage(const occseg_result *result, uint32_t index, const char **stage,
                                   double *seconds);

/* Writes `dir`/labels.npy (uint32 [z, y, x]) and `dir`/segments.json, the same files as
 * `occseg segment --out dir`, creating `dir` (not its parents) if missing.
 *
 * All or nothing: when the call returns, `dir` holds either what it held before, each of the two
 * files unchanged (or absent, as before), or the complete new pair; never one new and one old
 * file, a partial file or a temporary file. How:
 *   1. Both files are written completely to new temporaries in `dir`, named `NAME.tmp-` and 16
 *      random hex digits and created with O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, so a file
 *      or symbolic link planted under such a name is never opened (another name is drawn); their
 *      final mode is 0666 less the umask, as for any new file. Each is flushed and fsync'd. A
 *      failure here (OCCSEG_EIO naming the file and the reason: a full disk, a quota,
 *      RLIMIT_FSIZE "File too large", no permission; OCCSEG_ENOMEM) removes the temporaries and,
 *      if this call created `dir`, `dir`; no old file has been touched.
 *   2. In one short step, with SIGINT, SIGTERM, SIGHUP and SIGQUIT blocked on the calling thread
 *      (a signal arriving then is delivered after it; the masks of other threads are theirs),
 *      each temporary is swapped with the file it replaces (renameat2 RENAME_EXCHANGE) and the
 *      old version deleted; then `dir` is fsync'd. If a rename fails in this step, the file
 *      swapped before it is swapped back, and the call fails with OCCSEG_EIO naming the file. On
 *      a file system without RENAME_EXCHANGE a plain rename is used, which cannot be undone: the
 *      message then names the file already replaced.
 * Not covered: the process being killed (SIGKILL, or a fatal signal taken by another thread) or
 * the machine failing during step 2; each file is then old or new, and temporaries may remain.
 * The library never changes signal dispositions: beyond RLIMIT_FSIZE the kernel sends SIGXFSZ,
 * whose default action ends the process; a program that wants OCCSEG_EIO instead ignores SIGXFSZ
 * (as the occseg command does). */
OCCSEG_API int occseg_result_write(const occseg_result *result, const char *dir);

/* ========================================================================================== */
/*  Plugins                                                                                   */
/* ========================================================================================== */

/* Plugins add texture operators, histogram similarities, map readers/writers (by file
 * extension) and parameters at run time; occseg_plugin.h is the ABI they are written against and
 * docs/plugins.md explains it. The built-in stages are registered the same way, as the plugins
 * "builtin" (texture lbp6, lbp8; similarity g, chi2) and "builtin_io" (.npy, .nrrd; .yaml read).
 *
 * Thread safety: loading is serialised and transactional (a plugin's stages and parameters
 * appear all at once, or not at all if it fails), and loaded plugins are never unloaded, so
 * plugins may be loaded while other threads segment, read maps or enumerate; a segmentation
 * uses the stages that were registered when it started. Enumeration indices are stable (lists
 * only grow) and the strings returned live until the process exits. */

/* Loads one plugin file (a shared object exporting occseg_plugin_entry). Fails with
 * OCCSEG_EPLUGIN, and a last-error text naming the file and the reason, when it cannot be
 * opened (with the dlerror() text), is not a regular file (a FIFO, a device: refused before
 * dlopen, which would wait for a FIFO's writer forever), has no entry point, was built for another plugin ABI major
 * or a newer minor, uses a plugin, stage, extension or parameter name that is already taken, or
 * its register function fails; the registry is then unchanged. */
OCCSEG_API int occseg_plugins_load(const char *path);

/* Loads every *.so file of the plugin search path (also done once, by itself, at the first read
 * or write of an extension nothing serves: see occseg_map_read_options): the folders of the environment variable
 * OCCSEG_PLUGIN_PATH (colon-separated), then the install's <libdir>/occseg/plugins (found
 * next to the loaded liboccseg, so relocated installs work, then at the configured prefix).
 * A plugin whose name is already loaded is skipped (the first in the path wins). All files are
 * tried (a *.so that is not a regular file fails without being opened); if any fails, returns OCCSEG_EPLUGIN with every failure in the last-error text.
 * `loaded` (may be NULL) receives the number of plugins loaded by this call. */
OCCSEG_API int occseg_plugins_load_default(uint32_t *loaded);

/* The search path of occseg_plugins_load_default, folders joined by ':'; snprintf-like, as
 * occseg_params_get. */
OCCSEG_API int occseg_plugin_search_path(char *buf, size_t size, size_t *length);

/* Loaded plugins, built-in ones first, in load order; NULL past the end. The path is "" for
 * plugins built into the library. */
OCCSEG_API uint32_t occseg_plugin_count(void);
OCCSEG_API const char *occseg_plugin_name(uint32_t index);
OCCSEG_API const char *occseg_plugin_version(uint32_t index);
OCCSEG_API const char *occseg_plugin_description(uint32_t index);
OCCSEG_API const char *occseg_plugin_path(uint32_t index);
/* The plugin ABI a plugin was built for. OCCSEG_ERANGE past the end. */
OCCSEG_API int occseg_plugin_abi(uint32_t index, uint32_t *major, uint32_t *minor);
/* The plugin ABI this library implements (OCCSEG_PLUGIN_ABI_MAJOR/MINOR of its occseg_plugin.h). */
OCCSEG_API void occseg_plugin_host_abi(uint32_t *major, uint32_t *minor);

/* Kinds of registered stages. */
typedef enum {
  OCCSEG_STAGE_TEXTURE = 0,    /* texture operators: the parameter texture=NAME */
  OCCSEG_STAGE_SIMILARITY = 1, /* histogram similarities: the parameter similarity=NAME */
  OCCSEG_STAGE_READER = 2,     /* map readers: name is the extension, ".bt" */
  OCCSEG_STAGE_WRITER = 3      /* map writers: name is the extension */
} occseg_stage_kind;

/* Registered stages of one kind, in registration order (0 for a bad kind); name, one-line
 * description and the name of the plugin that registered it, NULL past the end. */
OCCSEG_API uint32_t occseg_stage_count(occseg_stage_kind kind);
OCCSEG_API const char *occseg_stage_name(occseg_stage_kind kind, uint32_t index);
OCCSEG_API const char *occseg_stage_description(occseg_stage_kind kind, uint32_t index);
OCCSEG_API const char *occseg_stage_plugin(occseg_stage_kind kind, uint32_t index);

/* Parameters declared by plugins follow the built-in ones in occseg_param_count/_name/...; these
 * give the plugin that declared parameter `index` ("builtin" for the core's own; NULL past the
 * end) and its default value as text (snprintf-like, as occseg_params_get). */
OCCSEG_API const char *occseg_param_plugin(uint32_t index);
OCCSEG_API int occseg_param_default(uint32_t index, char *buf, size_t size, size_t *length);

/* occseg_map_read / occseg_map_write pick the reader or writer registered for the path's last
 * extension (case-insensitive): built in are .npy and .nrrd (and the reader .yaml), plugins add
 * others (.pcd, .bt, ...). The first read (write) of an extension no loaded reader (writer)
 * serves loads the plugin search path as occseg_plugins_load_default() does, once per process and
 * thread-safely, and looks again, so the installed plugins' formats need no load call; the
 * environment variable OCCSEG_NO_DEFAULT_PLUGINS=1 turns that off.
 * An extension nobody handles then fails with OCCSEG_EUNSUPPORTED naming it, the folders searched
 * and the call that would help (occseg_plugins_load, OCCSEG_PLUGIN_PATH). These variants pass
 * reader/writer options: NULL or a NULL-terminated array of "key=value" texts (see the reader's
 * documentation; unknown keys fail). */
OCCSEG_API int occseg_map_read_options(occseg_map **out, const char *path, const char *const *options);
OCCSEG_API int occseg_map_write_options(const occseg_map *map, const char *path, const char *const *options);

/* ========================================================================================== */
/*  Point clouds: fusion into a map, labels back on the points                                */
/* ========================================================================================== */

/* Clouds held in memory (an (N, 3) array from a depth camera driver, a ROS PointCloud2, Open3D)
 * fused into an occupancy map by ray casting, with the very code that fuses a .pcd file (the
 * pcl_reader plugin behind occseg_map_read): the same points with the same pose and options give
 * a bit-identical map. Model: OctoMap's log-odds inverse sensor model (hit 0.7, miss 0.4, clamped
 * to [0.12, 0.97]); every voxel a ray crosses gets a miss, the voxel holding its return a hit,
 * each voxel at most one update per scan and a hit winning over a miss; untouched voxels are 0.5.
 *
 * A point cloud is `count` points of three coordinates x, y, z of `dtype` (OCCSEG_F32 or
 * OCCSEG_F64; others fail with OCCSEG_EINVAL), point i at (const char *)points + i * stride with
 * its x, y, z consecutive (any alignment; stride 0: packed, 3 * element size; a negative stride
 * walks backwards from `points`; |stride| below a point's 3 elements fails with OCCSEG_EINVAL).
 * Its pose maps the points into the world frame, with the sensor at `origin`: world = R p +
 * origin, R the rotation of the quaternion `orientation_wxyz` = (w, x, y, z), as the command's
 * --sensor-origin and --sensor-orientation take it and a .pcd VIEWPOINT stores it. NULL origin
 * means (0, 0, 0), NULL orientation the identity (1, 0, 0, 0). The quaternion is normalised, as
 * the .pcd path does (so any non-zero multiple of a unit quaternion is the same rotation); a zero
 * or non-finite quaternion or a non-finite origin fails with OCCSEG_EVALUE. Points with a NaN or
 * infinite coordinate (the holes of an organized cloud) are skipped, as the .pcd path skips them.
 * Coordinates are moved by the pose in double and rounded to float relative to the grid's corner,
 * so a cloud at UTM-like coordinates keeps its precision.
 *
 * Thread safety: occseg_fusion_add_points changes the fusion, so it must not run while another
 * thread uses the same fusion; occseg_fusion_map and occseg_fusion_counts only read it and may
 * run on several threads at once. occseg_result_point_labels only reads the result and the map. */
typedef struct occseg_fusion occseg_fusion;

/* Options of a fusion. Set struct_size = sizeof(occseg_fusion_options) and the defaults with
 * OCCSEG_FUSION_OPTIONS_INIT or occseg_fusion_options_init(), then change fields. */
typedef struct {
  uint32_t struct_size;  /* sizeof(occseg_fusion_options); any other value fails with OCCSEG_EINVAL */
  int32_t threads;       /* worker threads, 0: one per core; the map never depends on it */
  double voxel_size;     /* metres per voxel edge, positive and finite (default 0.05, as .pcd) */
  double margin;         /* metres added on every side of a fitted box (default 0; unused with use_box) */
  double max_range;      /* metres; < 0: unlimited (default -1). Longer rays mark free space only */
  int32_t use_box;       /* nonzero: the grid is the fixed box below (else fitted, see occseg_fusion_map) */
  double box_min[3];     /* world corner of the box (the map's origin) */
  double box_max[3];     /* far corner: ceil((max - min) / voxel_size) voxels per axis */
} occseg_fusion_options;

#define OCCSEG_FUSION_OPTIONS_INIT \
  { (uint32_t)sizeof(occseg_fusion_options), 0, 0.05, 0.0, -1.0, 0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0} }

/* Sets *opts to the defaults above, struct_size included (for FFIs that cannot use the macro).
 * NULL is a no-op. */
OCCSEG_API void occseg_fusion_options_init(occseg_fusion_options *opts);

/* Starts a fusion (opts NULL: the defaults). The grid's bounds:
 *   - use_box: the box given, fixed up front (origin box_min, as the command's --bbox); each
 *     occseg_fusion_add_points ray-casts its scan into the grid at once (rays are clipped to the
 *     box, returns outside it only free space), so memory is the grid's (5 bytes a voxel), however
 *     many scans come; a box needing more than 2^40 voxels fails with OCCSEG_EDIMS here.
 *   - otherwise: fitted at the end to every scan, as the .pcd path fits one cloud: the smallest
 *     voxel-aligned box (corners multiples of voxel_size) holding every finite point and every
 *     sensor origin (a return beyond max_range counting up to max_range), padded by margin.
 *     The scans are buffered (a copy of their points, 12 bytes a point for F32, 24 for F64)
 *     and ray-cast, in the order added, by occseg_fusion_map.
 * Fails with OCCSEG_EINVAL (NULL out, bad struct_size, negative threads or margin, NaN
 * max_range), OCCSEG_EVALUE (voxel_size not positive and finite; an empty, inverted, non-finite
 * or out-of-range box), OCCSEG_EDIMS, OCCSEG_ENOMEM. */
OCCSEG_API int occseg_fusion_new(occseg_fusion **out, const occseg_fusion_options *opts);

/* Frees a fusion and its buffered scans. NULL is a no-op. */
OCCSEG_API void occseg_fusion_free(occseg_fusion *fusion);

/* Adds one scan (see the section's text for points, strides and the pose). Scans accumulate:
 * call it once per scan of a robot's sequence, each with its own pose. A scan of only
 * non-finite points is accepted (it adds nothing but its sensor origin to a fitted box).
 * Fails, leaving the fusion as it was, with OCCSEG_EINVAL (NULL fusion or points, count 0, bad
 * dtype or stride, a stride whose extent overflows), OCCSEG_EVALUE (a bad pose; a point or
 * sensor more than 2^40 voxels from the world origin), OCCSEG_EDIMS (without use_box: the scans
 * so far would need a grid of more than 2^40 voxels, or an axis longer than that), OCCSEG_ENOMEM. */
OCCSEG_API int occseg_fusion_add_points(occseg_fusion *fusion, const void *points, occseg_dtype dtype, size_t count,
                                        ptrdiff_t stride, const double origin[3], const double orientation_wxyz[4]);

/* The map of every scan added so far, as a new map the caller frees (the fusion goes on: more
 * scans may follow, and a later call gives the map of all of them). Without use_box the
 * buffered scans are ray-cast here, into the box fitted to all of them, which costs a whole
 * fusion per call. Fails with OCCSEG_EVALUE "no finite point" when no scan added a finite
 * point (as the .pcd path fails on a cloud of NaN), OCCSEG_ENOMEM. */
OCCSEG_API int occseg_fusion_map(occseg_map **out, const occseg_fusion *fusion);

/* Number of scans and of finite points added so far (either pointer may be NULL). */
OCCSEG_API int occseg_fusion_counts(const occseg_fusion *fusion, uint64_t *scans, uint64_t *points);

/* The label occseg_result_point_labels gives a point no voxel holds. */
#define OCCSEG_NO_LABEL UINT32_MAX

/* Labels back on the input: out[i] = the segment id of the voxel input point i lies in, or
 * OCCSEG_NO_LABEL when the point has a non-finite coordinate or lies outside the grid. Points,
 * stride, dtype and pose as for occseg_fusion_add_points (pass the pose the scan was fused
 * with); the voxel is computed exactly as the fusion computes the voxel of the point's return,
 * so every point of a fused scan gets the label of the voxel its return went into. For an
 * organized cloud (rows of width points, in row order) out is a label image of the same shape.
 * The grid's geometry (voxel size, origin) is that of `map` (dims must equal the result's, else
 * OCCSEG_EINVAL), or with map == NULL the one the map had when occseg_segment (or
 * occseg_context_segment) made the result. `out_count` is the capacity of `out` in elements;
 * less than `count` fails with OCCSEG_ERANGE. Other failures as occseg_fusion_add_points. */
OCCSEG_API int occseg_result_point_labels(const occseg_result *result, const occseg_map *map, const void *points,
                                          occseg_dtype dtype, size_t count, ptrdiff_t stride, const double origin[3],
                                          const double orientation_wxyz[4], uint32_t *out, size_t out_count);

/* ========================================================================================== */
/*  Oriented boxes of segments (boxes to plan with)                                           */
/* ========================================================================================== */

/* A box in the map's world frame, in metres: a point at local coordinates q (within
 * +-extents / 2 on each axis) lies at center + R q, R the rotation of `quaternion`. */
typedef struct {
  uint32_t struct_size;   /* set by the caller to sizeof(occseg_box) */
  double center[3];       /* metres, world frame (the map's origin and voxel size applied) */
  double extents[3];      /* full edge lengths in metres along the box's axes */
  double quaternion[4];   /* w, x, y, z: unit rotation from the map's axes to the box's, w >= 0 */
} occseg_box;

/* Fills `*out` with the oriented bounding box of segment `index` (0 .. count - 1; OCCSEG_ERANGE
 * beyond). out->struct_size must be sizeof(occseg_box) of a version of this header
 * (OCCSEG_EINVAL otherwise). Occupied segments: the smallest box (by volume) holding every voxel
 * whole, among the map's axes, the principal axes of the voxel centres and the minimum-area turn
 * about z; ties keep the map's axes, so an axis-aligned object gets the identity rotation and
 * exactly its voxel box. Free and unknown segments: their axis-aligned voxel box. The boxes of
 * all segments are computed on the first call (one pass over the labels; OCCSEG_ENOMEM when the
 * occupied voxels' list does not fit) and kept in the result; they depend on the labels only,
 * never on the thread count. Safe to call from several threads at once. */
OCCSEG_API int occseg_result_segment_box(const occseg_result *result, uint32_t index, occseg_box *out);

/* ========================================================================================== */
/*  Writing the command's output files                                                        */
/* ========================================================================================== */

/* Writes into `dir` the output files of `occseg segment --out dir` named in `names` (a
 * NULL-terminated array of file names), as the command writes them: "labels.npy",
 * "labels.nrrd" (uint32 labels with the map's voxel size and origin, in the named space of a map
 * read from a .nrrd file), "segments.json" (with the map's frame and the oriented boxes),
 * "segments.ply" (the occupied segments' surfaces), and for 2D maps (nz = 1)
 * "segmentation.pgm" and "segmentation.yaml" (a map_server map). NULL `names`: the command's
 * default set that the library can write: labels.nrrd, segments.json and, for a 2D map, the PGM
 * and YAML pair. The pictures, segments.ot and the point clouds need libraries liboccseg does
 * not link (libpng, OctoMap, PCL) or the input itself: naming one fails with OCCSEG_EUNSUPPORTED;
 * any other name, a name given twice, or a 2D file for a 3D map fails with OCCSEG_EINVAL naming
 * it, before anything is written. All or nothing, exactly as occseg_result_write (creates `dir`,
 * not its parents; on failure every file in `dir` is as it was). */
OCCSEG_API int occseg_result_write_outputs(const occseg_result *result, const char *dir, const char *const *names);

/* ========================================================================================== */
/*  Borrowed buffers: maps that view the caller's array, results read in place                */
/* ========================================================================================== */

/* Makes a map that reads the caller's buffer where it lies, instead of copying it as
 * occseg_map_from_buffer_flags does. The arguments, their checks and their status codes are
 * those of occseg_map_from_buffer_flags (strides in bytes, NULL: dense with x fastest; any
 * occseg_dtype; the import flags), except that the values are not read here: they are checked
 * as a call reads them, and a bad one fails that call (occseg_segment, occseg_context_segment,
 * occseg_map_values, occseg_map_write) with the status and the text occseg_map_from_buffer_flags
 * gives for the same buffer ("data: probability at voxel (x, y, z) = ... is NaN ...").
 *
 * Lifetime: the map refers to `data`; it holds no copy. The caller keeps the buffer alive, and
 * its values unchanged, from this call until occseg_map_free(map); writing into it while a call
 * reads the map is a data race, and freeing it first leaves the map dangling (any later use reads
 * freed memory). Results do not refer to the map or the buffer: they may outlive both.
 *
 * Cost: a dense float32 buffer with x fastest (a C-order NumPy float32 array [z, y, x]) in the
 * machine's byte order is read by the pipeline itself, in its first pass, with no copy at all.
 * occseg_segment and occseg_context_segment read any other dtype, layout or byte order, and a
 * float32 buffer under import flags that holds a value the flags must change (it is first
 * scanned for one), through a converter: the stages convert the rows and planes they read into
 * scratch of their own (three planes per thread at most), with the values and the checks of the
 * copy path, so no float copy of the map is made either. occseg_map_values converts into the
 * caller's array; occseg_map_write and a plugin's texture operator (which take a float array)
 * get a temporary float copy (4 bytes per voxel during the call, nothing between calls). */
OCCSEG_API int occseg_map_view_buffer(occseg_map **out, const void *data, occseg_dtype dtype,
                                      const size_t dims[3] /* nx, ny, nz */,
                                      const ptrdiff_t strides[3] /* bytes; NULL: dense, x fastest */,
                                      double voxel_size, uint32_t flags);

/* The result's labels where they lie: `*out` receives a pointer to its nx * ny * nz uint32
 * labels (x fastest) and `*count` their number, without a copy. The pointer stays valid, and
 * the labels unchanged, until the result is freed (occseg_result_free) or recycled
 * (occseg_context_recycle); it must not be used after that. On failure (a NULL argument:
 * OCCSEG_EINVAL) `*out` is set to NULL and `*count` to 0 where they are not NULL. */
OCCSEG_API int occseg_result_labels_view(const occseg_result *result, const uint32_t **out, size_t *count);

/* The voxels' states (occseg_state values, uint8, x fastest) as an array the result owns: made
 * on the first call (1 byte per voxel, kept with the result; several threads may ask at once),
 * then returned as it is. Valid, like the labels view, until the result is freed or recycled.
 * OCCSEG_ENOMEM if the array cannot be made (a later call tries again). */
OCCSEG_API int occseg_result_states_view(const occseg_result *result, const uint8_t **out, size_t *count);

/* The segment table as an array the result owns: `*count` entries, entry i as
 * occseg_result_segment(result, i, ...) fills it (struct_size = sizeof(occseg_segment_info) of
 * this library; padding bytes zero), made on the first call (once, as above) and kept with the
 * result; valid until the result is freed or recycled. For bindings that read the whole table at
 * once. OCCSEG_ENOMEM if it cannot be made (a later call tries again). */
OCCSEG_API int occseg_result_segments_view(const occseg_result *result, const occseg_segment_info **out,
                                           size_t *count);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* OCCSEG_OCCSEG_H */
