// The reference renderer's motion direction of one bench_imaging_maps rig view (RenderReferenceRigView's rng:
// Clutter's 48 draws, then CameraPipeline's angle, rad, of the line in image x/y). stdin: the view's seed
// (1000003 * row + 1009 * camera + seq) per line; stdout: "seed angle". Used by 2026-12-07-motionmap-split.py.
#include <cmath>
#include <cstdio>
#include <random>
int main() {
  unsigned long long seed;
  while (std::scanf("%llu", &seed) == 1) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (int i = 0; i < 48; ++i) uni(rng);
    const double a = std::uniform_real_distribution<double>(0, M_PI)(rng);
    std::printf("%llu %.6f\n", seed, a);
  }
}
