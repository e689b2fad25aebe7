// Times one level of OpenSubdiv uniform refinement (topology + vertex interpolation in double
// precision) of an OBJ mesh, for benches/peers/mesh_peers.py.
// Usage: osd_bench loop|catmark file.obj [repeats]  → prints best seconds
// Build: g++ -O2 -std=c++14 osd_bench.cpp -losdCPU -o osd_bench
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

using namespace OpenSubdiv;

struct Vertex {
    double p[3];
    void Clear(void * = 0) { p[0] = p[1] = p[2] = 0.0; }
    void AddWithWeight(Vertex const &src, double w) {
        p[0] += w * src.p[0];
        p[1] += w * src.p[1];
        p[2] += w * src.p[2];
    }
};

int main(int argc, char **argv) {
    if (argc < 3) return 2;
    bool loop = std::strcmp(argv[1], "loop") == 0;
    int reps = argc > 3 ? std::atoi(argv[3]) : 3;
    FILE *f = std::fopen(argv[2], "r");
    if (!f) return 2;
    std::vector<Vertex> verts;
    std::vector<int> nper, idx;
    char line[4096];
    while (std::fgets(line, sizeof line, f)) {
        if (line[0] == 'v' && line[1] == ' ') {
            Vertex v;
            std::sscanf(line + 2, "%lf %lf %lf", &v.p[0], &v.p[1], &v.p[2]);
            verts.push_back(v);
        } else if (line[0] == 'f' && line[1] == ' ') {
            int n = 0;
            char *s = line + 2;
            while (*s) {
                while (*s == ' ') ++s;
                if (*s < '0' || *s > '9') break;
                idx.push_back(std::strtol(s, &s, 10) - 1);
                while (*s && *s != ' ') ++s;
                ++n;
            }
            nper.push_back(n);
        }
    }
    std::fclose(f);
    double best = 1e30;
    for (int r = 0; r < reps; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        Sdc::Options options;
        options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
        Far::TopologyDescriptor desc;
        desc.numVertices = (int)verts.size();
        desc.numFaces = (int)nper.size();
        desc.numVertsPerFace = nper.data();
        desc.vertIndicesPerFace = idx.data();
        Far::TopologyRefiner *refiner = Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Create(
            desc, Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Options(
                      loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK, options));
        refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(1));
        std::vector<Vertex> buf(refiner->GetNumVerticesTotal());
        std::copy(verts.begin(), verts.end(), buf.begin());
        Vertex *src = buf.data(), *dst = buf.data() + verts.size();
        Far::PrimvarRefinerReal<double>(*refiner).Interpolate(1, src, dst);
        auto t1 = std::chrono::steady_clock::now();
        double s = std::chrono::duration<double>(t1 - t0).count();
        if (s < best) best = s;
        delete refiner;
    }
    std::printf("%.6f\n", best);
    return 0;
}
