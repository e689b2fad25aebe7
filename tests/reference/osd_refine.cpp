// Uniform refinement with OpenSubdiv (Far), for the mesh reference fixtures.
// Reads from stdin:
//   scheme(loop|catmark) levels nverts nfaces ncreases ncorners
//   nverts lines "x y z"; nfaces lines "n i0 ... i{n-1}"; ncreases lines "a b"; ncorners lines "v"
// Creases and corners are infinitely sharp; boundaries: VTX_BOUNDARY_EDGE_ONLY.
// Writes to stdout: "nverts nfaces", the refined vertices (%.17g), then faces "n i0 ...".
// Build: g++ -O2 -std=c++14 osd_refine.cpp -losdCPU -o osd_refine
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

using namespace OpenSubdiv;

struct Vertex {
    double p[3];
    void Clear(void * = 0) { p[0] = p[1] = p[2] = 0.0; }
    void AddWithWeight(Vertex const &src, double w) {
        for (int k = 0; k < 3; ++k) p[k] += w * src.p[k];
    }
};

int main() {
    std::string scheme;
    int levels, nv, nf, nc, nk;
    std::cin >> scheme >> levels >> nv >> nf >> nc >> nk;
    std::vector<Vertex> coarse(nv);
    for (auto &v : coarse) std::cin >> v.p[0] >> v.p[1] >> v.p[2];
    std::vector<int> nper(nf), idx;
    for (int f = 0; f < nf; ++f) {
        std::cin >> nper[f];
        for (int i = 0; i < nper[f]; ++i) {
            int x;
            std::cin >> x;
            idx.push_back(x);
        }
    }
    std::vector<int> creases(2 * nc), corners(nk);
    for (auto &c : creases) std::cin >> c;
    for (auto &c : corners) std::cin >> c;
    std::vector<float> cw(nc, Sdc::Crease::SHARPNESS_INFINITE), kw(nk, Sdc::Crease::SHARPNESS_INFINITE);

    Sdc::SchemeType type = scheme == "loop" ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK;
    Sdc::Options options;
    options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
    Far::TopologyDescriptor desc;
    desc.numVertices = nv;
    desc.numFaces = nf;
    desc.numVertsPerFace = nper.data();
    desc.vertIndicesPerFace = idx.data();
    desc.numCreases = nc;
    desc.creaseVertexIndexPairs = nc ? creases.data() : nullptr;
    desc.creaseWeights = nc ? cw.data() : nullptr;
    desc.numCorners = nk;
    desc.cornerVertexIndices = nk ? corners.data() : nullptr;
    desc.cornerWeights = nk ? kw.data() : nullptr;
    Far::TopologyRefiner *refiner = Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Create(
        desc, Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Options(type, options));
    if (!refiner) return 1;
    refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
    std::vector<Vertex> buf(refiner->GetNumVerticesTotal());
    for (int i = 0; i < nv; ++i) buf[i] = coarse[i];
    Far::PrimvarRefinerReal<double> primvar(*refiner);
    Vertex *src = buf.data();
    for (int level = 1; level <= levels; ++level) {
        Vertex *dst = src + refiner->GetLevel(level - 1).GetNumVertices();
        primvar.Interpolate(level, src, dst);
        src = dst;
    }
    Far::TopologyLevel const &last = refiner->GetLevel(levels);
    std::printf("%d %d\n", last.GetNumVertices(), last.GetNumFaces());
    for (int i = 0; i < last.GetNumVertices(); ++i)
        std::printf("%.17g %.17g %.17g\n", src[i].p[0], src[i].p[1], src[i].p[2]);
    for (int f = 0; f < last.GetNumFaces(); ++f) {
        Far::ConstIndexArray fv = last.GetFaceVertices(f);
        std::printf("%d", fv.size());
        for (int i = 0; i < fv.size(); ++i) std::printf(" %d", fv[i]);
        std::printf("\n");
    }
    delete refiner;
    return 0;
}
