// Real-valued signals over the current segment of dense time: robustness
// values, with the same pieces and zip as the Boolean signals.
#pragma once

#include "engine/dense/signal.hpp"

namespace rvc::engine::robust {

using RealPiece = dense::BasicPiece<double>;
using RealSignal = dense::BasicSignal<double>;
using dense::zip;

}  // namespace rvc::engine::robust
