// Chooses the texture stage's kernels for a level (kernels.hpp).
#include "kernels/texture.hpp"

namespace occseg::kernels {

void select_texture(TextureKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
