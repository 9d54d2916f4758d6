// bench/peer/igl_arap_panels.cpp -- libigl's ARAP on given panels, for
// bench/bench_truth (issue 17: "as true as the best peer").
//
//   igl_arap_panels IN.obj OUT.obj [ITERATIONS=100]
//
// IN.obj: a flattening written by `panelize flatten ... --panels uv`
// (garment.obj: 3D `v`, per-corner `vt`, `f v/vt ...`). The panels are the
// connected components of the faces joined through shared vt indices (the
// cut mesh: one vt per panel vertex). Per panel, as the peer benchmark's
// `arap` mode (../shared/peers/igl_bench.cpp) does for one mesh: igl::lscm
// with two boundary pins (boundary vertex 0 and the one half way round)
// at their 3D distance apart, scaled to the panel's 3D area, then
// igl::arap_precomputation (2D, ELEMENTS energy, no dynamics) and
// igl::arap_solve for ITERATIONS iterations with boundary vertex 0 held.
// The input's vt are not used as a start. OUT.obj: IN.obj's lines with
// every `vt` replaced by the ARAP coordinates (same order, same faces), so
// `gtpattern.py compare TRUE.obj OUT.obj` reads it.
//
// This is a benchmark peer, not part of panelize: it is built only by the
// `igl_truth_peer` target from the headers in ../shared/peers/libigl (never
// copied into the project), and only C++ because libigl is.
//
// SPDX-License-Identifier: GPL-3.0-or-later
#include <igl/arap.h>
#include <igl/boundary_loop.h>
#include <igl/lscm.h>
#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct corner_mesh {
  std::vector<Eigen::Vector3d> positions;  // v
  std::vector<int> vt_position;            // per vt: its v index (-1 when unused)
  std::vector<std::array<int, 3>> faces;   // vt indices (fan-triangulated)
  std::vector<std::string> lines;          // the file, to write back
  int vt_count = 0;
};

int find_root(std::vector<int> &parent, int a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}

bool read_obj(const char *path, corner_mesh &mesh) {
  std::ifstream in(path);
  if (!in) return false;
  std::string line;
  while (std::getline(in, line)) {
    mesh.lines.push_back(line);
    std::istringstream words(line);
    std::string kind;
    words >> kind;
    if (kind == "v") {
      Eigen::Vector3d p;
      words >> p[0] >> p[1] >> p[2];
      mesh.positions.push_back(p);
    } else if (kind == "vt") {
      ++mesh.vt_count;
    } else if (kind == "f") {
      std::vector<int> vs, ts;
      std::string corner;
      while (words >> corner) {
        size_t slash = corner.find('/');
        if (slash == std::string::npos) return false;
        vs.push_back(std::atoi(corner.c_str()) - 1);
        ts.push_back(std::atoi(corner.c_str() + slash + 1) - 1);
      }
      for (size_t k = 1; k + 1 < vs.size(); ++k) {
        mesh.faces.push_back({ts[0], ts[k], ts[k + 1]});
        for (size_t c : {size_t(0), k, k + 1}) {
          if (ts[c] < 0 || vs[c] < 0) return false;
          if ((int)mesh.vt_position.size() <= ts[c]) mesh.vt_position.resize(ts[c] + 1, -1);
          mesh.vt_position[ts[c]] = vs[c];
        }
      }
    }
  }
  return !mesh.faces.empty();
}

double triangle_area(const Eigen::MatrixXd &P, int a, int b, int c) {
  if (P.cols() == 3) {
    Eigen::Vector3d e1 = (P.row(b) - P.row(a)).transpose(), e2 = (P.row(c) - P.row(a)).transpose();
    return 0.5 * e1.cross(e2).norm();
  }
  Eigen::RowVector2d e1 = P.row(b) - P.row(a), e2 = P.row(c) - P.row(a);
  return 0.5 * std::fabs(e1(0) * e2(1) - e1(1) * e2(0));
}

// ARAP of one panel (local vertices V, faces F) into UV.
bool flatten_panel(const Eigen::MatrixXd &V, const Eigen::MatrixXi &F, int iterations, Eigen::MatrixXd &UV) {
  Eigen::VectorXi boundary;
  igl::boundary_loop(F, boundary);
  if (boundary.size() < 3) return false;
  Eigen::VectorXi pins(2);
  pins << boundary(0), boundary(boundary.size() / 2);
  Eigen::MatrixXd pin_uv(2, 2);
  pin_uv << 0, 0, (V.row(pins(0)) - V.row(pins(1))).norm(), 0;
  if (!igl::lscm(V, F, pins, pin_uv, UV)) return false;
  double area3 = 0, area2 = 0;
  for (int f = 0; f < F.rows(); ++f) {
    area3 += triangle_area(V, F(f, 0), F(f, 1), F(f, 2));
    area2 += triangle_area(UV, F(f, 0), F(f, 1), F(f, 2));
  }
  UV *= std::sqrt(area3 / area2);
  Eigen::VectorXi held(1);
  held << boundary(0);
  Eigen::MatrixXd held_uv = UV.row(boundary(0));
  igl::ARAPData data;
  data.with_dynamics = false;
  data.max_iter = iterations;
  if (!igl::arap_precomputation(V, F, 2, held, data)) return false;
  return igl::arap_solve(held_uv, data, UV);
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: igl_arap_panels IN.obj OUT.obj [ITERATIONS]\n");
    return 64;
  }
  const int iterations = argc > 3 ? std::atoi(argv[3]) : 100;
  corner_mesh mesh;
  if (!read_obj(argv[1], mesh) || (int)mesh.vt_position.size() > mesh.vt_count) {
    fprintf(stderr, "igl_arap_panels: %s: not an OBJ with v/vt faces\n", argv[1]);
    return 65;
  }
  const int n = mesh.vt_count;
  std::vector<int> parent(n);
  for (int i = 0; i < n; ++i) parent[i] = i;
  for (const auto &f : mesh.faces)
    for (int k = 1; k < 3; ++k) parent[find_root(parent, f[k])] = find_root(parent, f[0]);
  std::vector<double> uv(2 * n, 0.0);
  std::vector<int> local(n, -1);
  std::vector<char> done(n, 0);
  int panels = 0;
  for (int root_vt = 0; root_vt < n; ++root_vt) {
    if (mesh.vt_position.size() <= (size_t)root_vt || mesh.vt_position[root_vt] < 0) continue;
    const int root = find_root(parent, root_vt);
    if (done[root]) continue;
    done[root] = 1;
    std::vector<int> members;
    for (int t = 0; t < (int)mesh.vt_position.size(); ++t)
      if (mesh.vt_position[t] >= 0 && find_root(parent, t) == root) {
        local[t] = (int)members.size();
        members.push_back(t);
      }
    std::vector<std::array<int, 3>> faces;
    for (const auto &f : mesh.faces)
      if (find_root(parent, f[0]) == root) faces.push_back({local[f[0]], local[f[1]], local[f[2]]});
    Eigen::MatrixXd V(members.size(), 3);
    for (size_t i = 0; i < members.size(); ++i) V.row(i) = mesh.positions.at(mesh.vt_position[members[i]]);
    Eigen::MatrixXi F(faces.size(), 3);
    for (size_t f = 0; f < faces.size(); ++f) F.row(f) << faces[f][0], faces[f][1], faces[f][2];
    Eigen::MatrixXd UV;
    if (!flatten_panel(V, F, iterations, UV)) {
      fprintf(stderr, "igl_arap_panels: %s: panel %d could not be flattened\n", argv[1], panels);
      return 70;
    }
    for (size_t i = 0; i < members.size(); ++i) {
      uv[2 * members[i]] = UV(i, 0);
      uv[2 * members[i] + 1] = UV(i, 1);
    }
    ++panels;
  }
  FILE *out = fopen(argv[2], "w");
  if (!out) {
    fprintf(stderr, "igl_arap_panels: %s: cannot create\n", argv[2]);
    return 73;
  }
  int vt = 0;
  for (const std::string &line : mesh.lines) {
    if (line.rfind("vt ", 0) == 0) {
      fprintf(out, "vt %.9g %.9g\n", uv[2 * vt], uv[2 * vt + 1]);
      ++vt;
    } else {
      fprintf(out, "%s\n", line.c_str());
    }
  }
  if (fclose(out) != 0) return 73;
  printf("igl_arap_panels panels=%d vt=%d iterations=%d\n", panels, n, iterations);
  return 0;
}
