/**
 * @file ToneMap.h
 * @brief Display colours of a linear radiance (W/mm^2/sr): one exposure
 * times the radiance, clamped to [0, 1], encoded with the sRGB transfer
 * curve (IEC 61966-2-1). The same mapping for the CLI's PNGs (`render
 * --png`, `compare`, `radiosity`) and the `RadianceRGB` array of
 * vtkOutgoingRadiance, so ParaView with Map Scalars off shows what the CLI
 * writes.
 */
#pragma once

#include <cstddef>
#include <vector>

namespace translucency
{

/// The sRGB encoding of a linear value, clamped to [0, 1] first.
double EncodeSRGB(double linear);

/**
 * The automatic exposure: 0.9 divided by the 99th percentile of the
 * per-point largest channel of `rgb` (3 values per point), so that 1 % of
 * the points saturate; 1 when that percentile is 0 or there are no points.
 */
double AutomaticExposure(const std::vector<double>& rgb);

/// 8-bit sRGB of exposure x `rgb` (3 values per point): 3 bytes per point.
std::vector<unsigned char> ToneMap(const std::vector<double>& rgb, double exposure);

} // namespace translucency
