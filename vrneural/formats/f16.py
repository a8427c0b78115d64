"""The float16 range every stage clamps and reports against (IEEE 754 binary16)."""

#: the largest finite float16; textures, BTF values and radiance are clamped into [0, F16_MAX]
F16_MAX = 65504.0
#: the smallest normal float16 (2^-14, 6.1e-5); smaller non-zero values are subnormal
F16_MIN_NORMAL = 2.0**-14
