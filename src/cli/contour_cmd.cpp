// keymesh contour IN -o OUT --iso V [...]: marching cubes welded by KEY-REDUCE.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "command.hpp"
#include "raw_input.hpp"
#include "keymesh/analyze/topology.hpp"
#include "keymesh/backend/contour.hpp"
#include "keymesh/generate/contour.hpp"
#include "keymesh/generate/contour_stream.hpp"
#include "keymesh/generate/contour_tets.hpp"
#include "contour_distributed.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct ContourCli {
  std::string input, output;
  std::vector<double> isovalues;
  std::string weld = "keyreduce";
  std::string normals = "none";
  bool no_scalars = false;
  bool coarsen = false;
  bool curvature = false;
  std::string array;  // tet grids: the point field to contour
  std::string memory_limit;  // stream the volume in slabs
  bool gather = false;       // under mpirun: one file from rank 0
  bool balance = false;      // under mpirun: slabs by work
  // Raw input description.
  RawInputCli raw_input;
  CommonOptions common;
};

Register reg{Command{
    "contour", "isosurface of a volume (marching cubes) or a tet grid (marching tetrahedra), welded by edge keys",
    [](CLI::App& cmd) -> std::function<int()> {
      auto o = std::make_shared<ContourCli>();
      cmd.add_option("input", o->input,
                     "volume: .vti .nrrd .nhdr .nii .nii.gz .den, a DICOM or Zarr folder, or raw with --dims; "
                     "or a tetrahedral grid: .vtu, .vtk (UNSTRUCTURED_GRID)")
          ->required();
      cmd.add_option("--array", o->array, "tet grids: the point field to contour (default: the first scalar field)");
      cmd.add_option("-o,--output", o->output, "output mesh (.vtp .ply .obj .stl .glb; under mpirun also .pvtp: one piece per rank)")->required();
      cmd.add_option("--iso", o->isovalues, "isovalue (repeat for several)")->required()->expected(1, -1);
      cmd.add_option("--weld", o->weld,
                     "how to connect the soup: keyreduce (edge keys, structured plan: cut edges counted per row, no soup; default), "
                     "keyreduce-sort (KEY-REDUCE with the sort plan), "
                     "or vertexweld (coordinates, the paper's baseline)")
          ->check(CLI::IsMember({"keyreduce", "keyreduce-sort", "vertexweld"}));
      cmd.add_option("--normals", o->normals,
                     "point normals: none, gradient (interpolated central differences) or average "
                     "(incident face normals merged by KEY-REDUCE)")
          ->check(CLI::IsMember({"none", "gradient", "average"}));
      cmd.add_flag("--no-scalars", o->no_scalars, "do not carry the interpolated scalar");
      cmd.add_flag("--curvature", o->curvature,
                   "mean curvature per point from the volume's gradient and Hessian (point field mean_curvature; "
                   "1/r on a sphere of the distance field); voxel grids only");
      cmd.add_flag("--coarsen", o->coarsen,
                   "merge the points nearest to one grid point (key = nearest input point on the edge), "
                   "averaging positions and fields; drop collapsed triangles");
      o->raw_input.add_options(cmd);
      cmd.add_option("--memory-limit", o->memory_limit,
                     "stream the volume in slabs of z-planes holding at most SIZE bytes of samples (e.g. 256M, 2G); "
                     "the output is byte-identical (averaged normals: within float rounding); raw (--dims), "
                     ".nrrd/.nhdr or .nii with uncompressed samples; no --coarsen")
          ->check(size_validator());
      cmd.add_flag("--gather", o->gather,
                   "under mpirun: gather the whole mesh on rank 0 into one file (the default unless OUT is .pvtp, "
                   "which writes one OUT_<rank>.vtp piece per rank with GlobalPointIds)");
      cmd.add_flag("--balance", o->balance,
                   "under mpirun: move the slab boundaries so that every rank gets about the same number of "
                   "triangles (counted on the equal split first); the output is the same");
      add_common_options(cmd, o->common);
      return [o]() {
        for (double iso : o->isovalues)
          if (!std::isfinite(iso)) {
            std::fprintf(stderr, "keymesh contour: --iso %g is not a finite number\n", iso);
            return 2;
          }
        const int threads = apply_threads(o->common);
        StageTimer timer;
        Progress progress(o->common.quiet, file_size(o->input) > (64ll << 20));
        const bool is_raw = o->raw_input.given();
        const io::RawOptions raw = is_raw ? o->raw_input.options() : io::RawOptions{};
        generate::ContourOptions opt;
        opt.isovalues = o->isovalues;
        opt.weld = o->weld == "vertexweld"       ? generate::ContourWeld::VertexWeld
                   : o->weld == "keyreduce-sort" ? generate::ContourWeld::KeyReduceSort
                                                 : generate::ContourWeld::KeyReduce;
        opt.normals = o->normals == "gradient"  ? generate::ContourNormals::Gradient
                      : o->normals == "average" ? generate::ContourNormals::Average
                                                : generate::ContourNormals::None;
        opt.scalars = !o->no_scalars;
        opt.array = o->array;
        opt.coarsen = o->coarsen;
        opt.max_output_bytes = memory_budget(o->common);
        opt.curvature = o->curvature;
        opt.backend = o->common.backend == "cuda" ? generate::Backend::Cuda : generate::Backend::Cpu;
        auto warn_outside = [&](std::array<double, 2> range) {
          for (double iso : o->isovalues)
            if ((iso < range[0] || iso > range[1]) && !o->common.quiet)
              std::fprintf(stderr, "keymesh: warning: isovalue %g is outside the data range [%g, %g]\n", iso,
                           range[0], range[1]);
        };
        generate::ContourStats stats;
        SurfaceMesh mesh;
        nlohmann::json r;
        if (distributed::size() > 1 || (distributed::launched_by_mpi() && is_raw && o->memory_limit.empty())) {
          // mpirun -np P keymesh contour VOLUME ...: each rank reads its slab.
          if (!is_raw && io::is_grid_file(o->input)) {
            if (distributed::rank() == 0)
              std::fprintf(stderr, "keymesh contour: %s: marching tetrahedra is not distributed; run it as one "
                                   "process\n", o->input.c_str());
            return 2;
          }
          if (!o->memory_limit.empty()) {
            if (distributed::rank() == 0)
              std::fprintf(stderr, "keymesh contour: --memory-limit is for one process; under mpirun each rank "
                                   "holds only its slab\n");
            return 2;
          }
          DistributedContourJob job;
          job.input = o->input;
          job.output = o->output;
          job.report_path = o->common.report_path;
          job.raw = raw;
          job.raw_given = is_raw;
          job.options = opt;
          job.gather = o->gather;
          job.balance = o->balance;
          job.quiet = o->common.quiet;
          job.threads = threads;
          job.weld = o->weld;
          job.normals = o->normals;
          return run_distributed_contour(job);
        }
        if (!o->memory_limit.empty()) {
          std::size_t limit = 0;
          parse_size(o->memory_limit, limit);  // checked by its validator
          auto source = io::open_volume_planes(o->input, is_raw ? &raw : nullptr);
          generate::StreamStats ss;
          mesh = timer.run("contour", [&] { return generate::contour_streamed(*source, opt, limit, &stats, &ss); });
          timer.add("read", ss.read);
          r["dims"] = source->header().dims;
          r["scalar_type"] = scalar_type_name(source->header().type);
          r["grid"] = "voxels";
          r["memory_limit"] = limit;
          r["stream"] = {{"slabs", ss.slabs}, {"planes_per_slab", ss.planes_per_slab},
                         {"slab_bytes", ss.slab_bytes}, {"read", ss.read}, {"contour", ss.contour},
                         {"merge", ss.merge}};
        } else if (!is_raw && io::is_grid_file(o->input)) {
          progress.say("reading " + o->input);
          if (opt.normals == generate::ContourNormals::Gradient || opt.curvature) {
            std::fprintf(stderr, "keymesh contour: %s needs a voxel grid%s\n",
                         opt.curvature ? "--curvature" : "--normals gradient",
                         opt.curvature ? "" : "; use --normals average");
            return 2;
          }
          const UnstructuredGrid grid = timer.run("read", [&] { return io::read_grid(o->input); });
          progress.enable_if(grid.num_cells() > (1ll << 26));
          for (const Field& f : grid.point_fields)
            if (o->array.empty() ? f.components == 1 : f.name == o->array) {
              std::array<double, 2> range{0, 0};
              bool any = false;
              for (float v : f.values)
                if (std::isfinite(v)) {
                  range = any ? std::array<double, 2>{std::min<double>(range[0], v), std::max<double>(range[1], v)}
                              : std::array<double, 2>{v, v};
                  any = true;
                }
              warn_outside(range);
              r["array"] = f.name;
              break;
            }
          progress.say("contouring " + std::to_string(grid.num_cells()) + " tetrahedra");
          mesh = timer.run("contour", [&] { return generate::contour(grid, opt, &stats); });
          r["input_points"] = grid.num_points();
          r["input_cells"] = grid.num_cells();
          r["grid"] = "tetrahedra";
        } else {
          progress.say("reading " + o->input);
          const ImageGrid grid =
              timer.run("read", [&] { return io::read_volume(o->input, is_raw ? &raw : nullptr); });
          progress.enable_if(grid.num_points() > (1ll << 25));
          warn_outside(scalar_range(grid));
          progress.say("contouring " + std::to_string(grid.dims[0]) + "x" + std::to_string(grid.dims[1]) + "x" +
                       std::to_string(grid.dims[2]) + " " + scalar_type_name(grid.type));
          mesh = timer.run("contour", [&] { return backend::contour(grid, opt, &stats); });
          r["dims"] = grid.dims;
          r["scalar_type"] = scalar_type_name(grid.type);
          r["grid"] = "voxels";
        }
        if (o->coarsen) {
          // What the collapse did to the topology (outside the contour's time).
          const auto topo = timer.run("check", [&] { return analyze::check_topology(mesh); });
          r["triangles_before"] = stats.triangles_before_coarsening;
          r["triangles_after"] = mesh.num_cells();
          r["nonmanifold_edges"] = topo.nonmanifold_edges;
          r["nonmanifold_vertices"] = topo.nonmanifold_vertices;
          r["boundary_edges"] = topo.boundary_edges;
          if (!o->common.quiet && (topo.nonmanifold_edges || topo.nonmanifold_vertices))
            std::fprintf(stderr, "keymesh: coarsening left %lld non-manifold edges and %lld non-manifold vertices\n",
                         (long long)topo.nonmanifold_edges, (long long)topo.nonmanifold_vertices);
        }
        progress.say("writing " + o->output);
        timer.run("write", [&] { io::write_mesh(mesh, o->output); });
        if (!o->common.quiet)
          std::fprintf(stderr, "keymesh: %lld points, %lld triangles -> %s\n", static_cast<long long>(mesh.num_points()),
                       static_cast<long long>(mesh.num_cells()), o->output.c_str());
        if (!o->common.report_path.empty()) {
          r["input"] = o->input;
          r["output"] = o->output;
          r["isovalues"] = o->isovalues;
          r["weld"] = o->weld;
          r["normals"] = o->normals;
          r["points"] = mesh.num_points();
          r["cells"] = mesh.num_cells();
          r["soup_points"] = stats.soup_points;
          r["key_bits"] = stats.key_bits;
          r["threads"] = threads;
          r["seconds"] = timer.seconds();
          r["coarsen"] = o->coarsen;
          r["contour_stages"] = {{"coarsen", stats.coarsen},
                                 {"classify", stats.classify},
                                 {"generate", stats.generate},
                                 {"weld", stats.weld},
                                 {"fields", stats.fields}};
          r["peak_rss_mib"] = peak_rss_mib();
          // What the run had to hold at least: the samples read and the mesh
          // written (MiB), beside its peak.
          double out_bytes = 4.0 * static_cast<double>(mesh.points.size() + mesh.connectivity.size()) +
                             8.0 * static_cast<double>(mesh.offsets.size());
          for (const Field& f : mesh.point_fields) out_bytes += 4.0 * static_cast<double>(f.values.size());
          r["output_mib"] = out_bytes / (1 << 20);
          if (r.contains("dims") && r.contains("scalar_type") && o->memory_limit.empty()) {
            double samples = 1;
            for (const auto& d : r["dims"]) samples *= d.get<double>();
            r["input_mib"] = samples * static_cast<double>(scalar_size(parse_scalar_type(r["scalar_type"]))) / (1 << 20);
          }
          if (opt.backend == generate::Backend::Cuda)
            r["device_peak_mib"] = static_cast<double>(stats.device_peak_bytes) / (1 << 20);
          write_report(o->common.report_path, r);
        }
        return 0;
      };
    }}};

}  // namespace

}  // namespace keymesh::cli
