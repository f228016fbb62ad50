#pragma once
// `keymesh labels`: what a run needs once the options are parsed, shared by
// the single-process command (labels_cmd.cpp) and the ranks of
// `mpirun -np P keymesh labels` (labels_distributed.cpp).
#include <array>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "command.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/generate/labels/labels_stream.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

// --format precomputed (labels_precomputed.cpp).
struct PrecomputedJob {
  bool on = false;
  int lods = 3;
  std::array<Id, 3> chunk_shape{32, 32, 32};
  bool sharded = false;
  bool chunk_given = false;  // --chunk I J K
  std::array<Id, 3> chunk{0, 0, 0};
  bool assemble = false;
  std::vector<std::array<Id, 3>> update;  // --update: the chunks changed
  // --label-names FILE, or the label table beside the input (IN.txt, or
  // IN without .gz + .txt, as MRIcron's atlases ship): segment names.
  std::string label_names;
  bool label_names_given = false;
};

struct LabelsJob {
  std::string input, output;
  std::string method;  // as given, for the report
  io::RawOptions raw;
  bool raw_given = false;
  generate::LabelOptions options;
  std::size_t memory_limit = 0;  // 0: the volume in memory (one process) or a rank's whole slab
  CommonOptions common;
  int threads = 1;
  PrecomputedJob precomputed;
};

// Runs f(), naming the input file in the generator's refusals ("labels: ..."
// becomes "IN: labels: ..."; the readers' errors name it already).
template <class F>
decltype(auto) naming_input(const LabelsJob& job, F&& f) {
  try {
    return f();
  } catch (const InputError& e) {
    if (std::string(e.what()).rfind("labels", 0) == 0) throw InputError(job.input + ": " + e.what());
    throw;
  }
}

// --max-memory: the samples and 16-bit label indices of padded rows
// [rows.first, rows.second) that the run holds (a --memory-limit slab at
// most), checked before they are allocated (LimitError). The surfaces come
// on top: their size is known only once they are made.
void check_labels_memory(const LabelsJob& job, const ImageGrid& header, std::pair<Id, Id> rows);

// Writes the mesh, the summary line and the report (`r` holds what the run
// adds: dims, scalar_type, stream, distributed); with --history (.vtp,
// checked) the history_key array beside the mesh's history_t field.
// stats.soup_corners and triangles_before_coarsening below 0 (not known)
// leave soup_points and triangles_before out.
void write_labels_outputs(const LabelsJob& job, const SurfaceMesh& mesh, const generate::LabelStats& stats,
                          nlohmann::json r, StageTimer& timer, const std::vector<std::uint64_t>& history_key = {});

// --format precomputed: Neuroglancer's multi-resolution meshes in the
// directory job.output (one call, a chunk task, the assembly or an update).
int run_labels_precomputed(const LabelsJob& job);

// Collective over the ranks: returns the exit code (every rank the same).
int run_distributed_labels(const LabelsJob& job);

// Collective, once the ranks agreed on the labels and their counts
// (labels_pieces.cpp): every rank writes its piece of OUT.pvtp (its padded
// rows `rows` and halo rows either side made, its share kept), rank 0 the
// index, the summary line and the report; nothing is gathered.
void write_labels_pieces(const LabelsJob& job, generate::LabelSlabs& slabs, const ImageGrid& header,
                         std::pair<Id, Id> rows, StageTimer& timer);

// Collective, as write_labels_pieces, for one output file
// (labels_gathered.cpp): every rank makes its share with halo rows as for
// pieces, and only the shares are gathered; rank 0 puts them together by
// global id and writes the one process's file byte for byte.
void write_labels_gathered(const LabelsJob& job, generate::LabelSlabs& slabs, const ImageGrid& header,
                           std::pair<Id, Id> rows, StageTimer& timer);

}  // namespace keymesh::cli
