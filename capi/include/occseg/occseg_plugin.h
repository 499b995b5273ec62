/*
 * occseg_plugin.h: the plugin ABI of occseg. A plugin is a shared object that liboccseg (or any
 * program embedding the occseg core, such as the `occseg` tool) loads at run time to add
 *   - texture operators       (the per-voxel code whose histograms the division compares),
 *   - histogram similarities  (how two histograms are compared when a block is tested),
 *   - map readers and writers (by file extension, for occseg_map_read / occseg_map_write),
 *   - named parameters        (settable like the built-in ones: occseg_params_set, --param).
 *
 * A plugin needs this header only: it never links against liboccseg. Everything it may call on
 * the host comes through the occseg_plugin_host table handed to its register function (as in
 * SQLite's sqlite3ext.h). Plain C99 types only; no variadic function.
 *
 * Writing one (see docs/plugins.md and plugins/example/):
 *
 *     #include <occseg/occseg_plugin.h>
 *     static int reg(const occseg_plugin_host *host, occseg_plugin_registrar *r) {
 *       occseg_plugin_similarity s = {sizeof s, "l1", "half the L1 distance", my_l1, NULL};
 *       return host->register_similarity(r, &s);
 *     }
 *     static const occseg_plugin_descriptor desc = {
 *         OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof desc,
 *         "mine", "1.0.0", "what it adds", reg};
 *     OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &desc; }
 *
 * Versioning
 *   The descriptor carries the plugin ABI the plugin was compiled for. The host accepts the same
 *   major and a minor not above its own. Within one major, structs and the host table only grow
 *   at their end: every struct begins with a size field (`struct_size`, set to sizeof by whoever
 *   fills it), so both sides can tell which fields exist.
 *
 * Lifetime
 *   Loaded plugins stay loaded until the process exits (their callbacks may be in use by any
 *   thread at any time). A plugin whose loading fails is unloaded again and leaves no trace.
 *   Strings and structs passed to the register functions are copied; they need not outlive the
 *   call. `user` pointers are passed back to the callbacks unchanged.
 *
 * Threads
 *   Register functions run under the host's loading lock, one at a time. Callbacks may be called
 *   from any thread and concurrently (the similarity callback in particular runs on the worker
 *   threads of the division): they must not modify shared state without their own locking.
 *   host->set_error stores the message per thread: call it on the thread that was called.
 */
#ifndef OCCSEG_OCCSEG_PLUGIN_H
#define OCCSEG_OCCSEG_PLUGIN_H

#include <stddef.h>
#include <stdint.h>

#include "occseg/occseg.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The plugin ABI this header describes (independent of the library version). */
#define OCCSEG_PLUGIN_ABI_MAJOR 1
#define OCCSEG_PLUGIN_ABI_MINOR 0

/* The one symbol a plugin exports, and its type. */
#define OCCSEG_PLUGIN_ENTRY_SYMBOL "occseg_plugin_entry"

#if defined(__GNUC__) && __GNUC__ >= 4
#  define OCCSEG_PLUGIN_VISIBLE __attribute__((visibility("default")))
#else
#  define OCCSEG_PLUGIN_VISIBLE
#endif
#ifdef __cplusplus
#  define OCCSEG_PLUGIN_EXPORT extern "C" OCCSEG_PLUGIN_VISIBLE
#else
#  define OCCSEG_PLUGIN_EXPORT OCCSEG_PLUGIN_VISIBLE
#endif

/* Texture code of a voxel that has no texture unit (e.g. on the map's outer faces). Such voxels
 * are left out of every histogram. */
#define OCCSEG_NO_TEXTURE 0xFFFFu

typedef struct occseg_plugin_host occseg_plugin_host;
/* Opaque, host-owned: collects a plugin's registrations until its register function returns. */
typedef struct occseg_plugin_registrar occseg_plugin_registrar;
/* Opaque, host-owned: receives the map a reader produces (host->map_alloc). */
typedef struct occseg_plugin_map_sink occseg_plugin_map_sink;

/* Passed to every callback. */
typedef struct {
  uint32_t struct_size;
  uint32_t threads;                 /* worker threads the callback may use (>= 1) */
  const occseg_plugin_host *host;   /* the host table (same as at registration) */
  void *user;                       /* the `user` pointer given at registration */
  const void *params;               /* host-private: for host->param_get_*; NULL in readers/writers */
} occseg_plugin_call;

/* A dense map handed to a callback: dims[0] * dims[1] * dims[2] probabilities in [0, 1],
 * index x + nx * (y + ny * z). Read-only. */
typedef struct {
  uint32_t struct_size;
  uint32_t reserved;                /* 0 */
  size_t dims[3];                   /* nx, ny, nz (a 2D map has nz = 1) */
  const float *values;
  double voxel_size;                /* metres per voxel edge */
  double origin[3];                 /* world position of the outer corner of voxel (0, 0, 0) */
} occseg_plugin_grid;

/* ---- Callbacks ---------------------------------------------------------------------------- */

/* Texture operator: writes one code per voxel into `codes` (caller-allocated, nx*ny*nz entries,
 * same index as the grid): a value in [0, K) or OCCSEG_NO_TEXTURE. Returns K, the number of
 * distinct codes (1 .. 65535; the histograms of the division have K bins), or a negative
 * OCCSEG_E* code after host->set_error. `contrast_bins` is the parameter b (2 .. 64). */
typedef int64_t (*occseg_plugin_texture_fn)(const occseg_plugin_call *call, const occseg_plugin_grid *grid,
                                            uint32_t contrast_bins, uint16_t *codes);

/* Histogram similarity: a dissimilarity of two histograms of `bins` counts, >= 0, 0 when they
 * are proportional (same distribution), larger the more they differ; the division splits a block
 * while max / min over the pairs of its octants exceeds split_ratio. A NaN or negative return
 * is reported as an error. Called concurrently from several threads. */
typedef double (*occseg_plugin_similarity_fn)(const occseg_plugin_call *call, const uint32_t *a,
                                              const uint32_t *b, size_t bins);

/* Map reader: reads `path` and delivers the map through host->map_alloc(sink, ...), filling the
 * returned buffer. `options` is NULL or a NULL-terminated array of "key=value" texts; a reader
 * must reject keys it does not know. Returns 0, or a negative OCCSEG_E* code after set_error. */
typedef int (*occseg_plugin_read_fn)(const occseg_plugin_call *call, const char *path,
                                     const char *const *options, occseg_plugin_map_sink *sink);

/* Map writer: writes `grid` to `path` (all or nothing). Returns 0 or a negative OCCSEG_E* code. */
typedef int (*occseg_plugin_write_fn)(const occseg_plugin_call *call, const char *path,
                                      const occseg_plugin_grid *grid, const char *const *options);

/* ---- What a plugin registers ------------------------------------------------------------- */

/* Names of stages and parameters: 1 to 63 characters of [a-z0-9_]. They share one namespace per
 * kind across all plugins: a name that is taken makes the whole plugin fail to load. */
typedef struct {
  uint32_t struct_size;             /* sizeof(occseg_plugin_texture) */
  const char *name;                 /* as used in the parameter texture=NAME */
  const char *description;          /* one line */
  occseg_plugin_texture_fn compute;
  void *user;
} occseg_plugin_texture;

typedef struct {
  uint32_t struct_size;             /* sizeof(occseg_plugin_similarity) */
  const char *name;                 /* as used in the parameter similarity=NAME */
  const char *description;
  occseg_plugin_similarity_fn compare;
  void *user;
} occseg_plugin_similarity;

/* Readers and writers are found by the file's last extension, case-insensitively. */
typedef struct {
  uint32_t struct_size;             /* sizeof(occseg_plugin_reader) */
  const char *extension;            /* with the dot: ".bt" */
  const char *description;
  occseg_plugin_read_fn read;
  void *user;
} occseg_plugin_reader;

typedef struct {
  uint32_t struct_size;             /* sizeof(occseg_plugin_writer) */
  const char *extension;
  const char *description;
  occseg_plugin_write_fn write;
  void *user;
} occseg_plugin_writer;

/* Kinds of declared parameters (the values are pinned). */
#define OCCSEG_PARAM_INT 0
#define OCCSEG_PARAM_DOUBLE 1
#define OCCSEG_PARAM_STRING 2

/* A named parameter: settable with occseg_params_set and the typed setters, --param NAME=VALUE
 * and Python keyword arguments; callbacks read it with host->param_get_*. Numbers must lie in
 * [min, max] (the default too); int values must be integral. */
typedef struct {
  uint32_t struct_size;             /* sizeof(occseg_plugin_param) */
  int32_t kind;                     /* OCCSEG_PARAM_INT, _DOUBLE or _STRING */
  const char *name;
  const char *default_value;        /* as text, e.g. "0.25" */
  double min, max;                  /* inclusive bounds of numbers (ignored for strings) */
  const char *description;          /* one line */
} occseg_plugin_param;

/* ---- The host table ------------------------------------------------------------------------ */

/* Functions the host offers. Append-only: a host of ABI minor m has every member of the minors
 * up to m; check struct_size before using members added after 1.0. The register_* and
 * declare_param functions may only be called during the register function; they return 0 or a
 * negative OCCSEG_E* code (bad name, taken name, bad struct) and then the plugin should return
 * that code, which makes the whole load fail. */
struct occseg_plugin_host {
  uint32_t struct_size;
  uint32_t abi_major, abi_minor;    /* of the host */
  int (*register_texture)(occseg_plugin_registrar *r, const occseg_plugin_texture *texture);
  int (*register_similarity)(occseg_plugin_registrar *r, const occseg_plugin_similarity *similarity);
  int (*register_reader)(occseg_plugin_registrar *r, const occseg_plugin_reader *reader);
  int (*register_writer)(occseg_plugin_registrar *r, const occseg_plugin_writer *writer);
  int (*declare_param)(occseg_plugin_registrar *r, const occseg_plugin_param *param);
  /* Sets the calling thread's error text; the host reads it when a callback or the register
   * function returns a failure, and puts it into occseg_last_error(). */
  void (*set_error)(const char *message);
  /* The value of any parameter (built-in or declared) during a stage callback. _int reads int
   * parameters, _double int and double ones; _string copies the value of any parameter as
   * text into buf (NUL-terminated; OCCSEG_ERANGE when size is too small). */
  int (*param_get_int)(const occseg_plugin_call *call, const char *name, int64_t *out);
  int (*param_get_double)(const occseg_plugin_call *call, const char *name, double *out);
  int (*param_get_string)(const occseg_plugin_call *call, const char *name, char *buf, size_t size);
  /* For readers: allocates the map (dims nx, ny, nz; voxel_size > 0; origin may be NULL for
   * (0, 0, 0)) and returns its value buffer, x fastest, initialised to 0.5, for the reader to
   * fill. Calling it again replaces the previous map. Values are checked after the reader
   * returns. */
  int (*map_alloc)(occseg_plugin_map_sink *sink, const size_t dims[3], double voxel_size,
                   const double origin[3], float **values);
  /* For texture operators: the built-in contrast quantiser. levels[i] = 0 for contrast[i] <= 0,
   * 1 .. bins-1 for positive contrasts in classes of equal frequency over all the positive
   * values given (the LBP/C rule of the built-in operators, ties kept together); NaN entries are
   * ignored and get OCCSEG_NO_TEXTURE. */
  int (*contrast_levels)(const double *contrast, size_t count, uint32_t bins, uint16_t *levels);
};

/* ---- The descriptor ------------------------------------------------------------------------ */

typedef struct {
  uint32_t abi_major, abi_minor;    /* OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR: first, forever */
  uint32_t struct_size;             /* sizeof(occseg_plugin_descriptor) */
  const char *name;                 /* [a-z0-9_], unique among loaded plugins */
  const char *version;              /* free text, e.g. "1.2.0" */
  const char *description;          /* one line */
  /* Registers everything the plugin offers through `host`; returns 0, or a negative OCCSEG_E*
   * code (after host->set_error) to refuse loading. */
  int (*register_plugin)(const occseg_plugin_host *host, occseg_plugin_registrar *registrar);
} occseg_plugin_descriptor;

/* The entry point every plugin exports under the name OCCSEG_PLUGIN_ENTRY_SYMBOL. It returns a
 * descriptor with static storage and must have no other effect. */
typedef const occseg_plugin_descriptor *(*occseg_plugin_entry_fn)(void);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* OCCSEG_OCCSEG_PLUGIN_H */
