"""Runtime: generated WGSL shading in texture space with reuse, stereo forward pass."""
