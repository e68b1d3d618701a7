// libbsdf_reflectance FORMAT FILE: libbsdf's reflectance of a LightTools or Zemax .bsdf per incidence.
// FORMAT is "lighttools" or "zemax". Prints one line per incidence of the file:
//   reflectance AOI_DEG NODES VALUE SPEC360 VALUE
// NODES: lb::computeReflectance(brdf, inThIndex, 0), libbsdf's quadrature on the file's own
//        nodes (Spherical: cell-corner mean x mid cos x cell solid angle; Specular: the
//        interpolated value at each cell's centroid x its z x the cell's solid angle on the
//        hemisphere);
// SPEC360: lb::computeReflectance(brdf, inDir) with its default 360 x 360 specular divisions
//        of the interpolated table.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <libbsdf/Brdf/Analyzer.h>
#include <libbsdf/Brdf/SphericalCoordinatesBrdf.h>
#include <libbsdf/Brdf/SpecularCoordinatesBrdf.h>
#include <libbsdf/Brdf/Bsdf.h>
#include <libbsdf/Brdf/Material.h>
#include <libbsdf/Brdf/TwoSidedMaterial.h>
#include <libbsdf/Common/Log.h>
#include <libbsdf/Common/SphericalCoordinateSystem.h>
#include <libbsdf/Reader/LightToolsBsdfReader.h>
#include <libbsdf/Reader/ZemaxBsdfReader.h>

template <typename B>
static void report(const B& brdf, int numInTheta)
{
    for (int i = 0; i < numInTheta; ++i) {
        double t = brdf.getInTheta(i);
        lb::Vec3 inDir = lb::SphericalCoordinateSystem::toXyz(std::max(t, 1e-10), 0.0);
        double nodes = lb::computeReflectance(brdf, i, 0)[0];
        double spec = lb::computeReflectance(static_cast<const lb::Brdf&>(brdf), inDir)[0];
        std::printf("reflectance %.6f %.9e %.9e\n", t * 180.0 / M_PI, nodes, spec);
    }
}

int main(int argc, char** argv)
{
    if (argc != 3) return 2;
    lb::Log::setNotificationLevel(lb::Log::Level::WARN_MSG);
    std::string format = argv[1];
    if (format == "lighttools") {
        std::unique_ptr<lb::TwoSidedMaterial> m(lb::LightToolsBsdfReader::read(argv[2]));
        if (!m) return 1;
        auto brdf = std::dynamic_pointer_cast<lb::SphericalCoordinatesBrdf>(
            m->getFrontMaterial()->getBsdf()->getBrdf());
        if (!brdf) return 1;
        report(*brdf, brdf->getNumInTheta());
    } else {
        lb::DataType type;
        std::unique_ptr<lb::SpecularCoordinatesBrdf> brdf(lb::ZemaxBsdfReader::read(argv[2], &type));
        if (!brdf) return 1;
        report(*brdf, brdf->getNumInTheta());
    }
    return 0;
}
