"""Which wgpu adapter vrneural uses (pure selection logic; the real adapter is in test_gpu_core)."""

from vrneural.gpu.device import pick_adapter


def _info(name, backend, kind):
    return {"device": name, "backend_type": backend, "adapter_type": kind}


def test_opengl_alone_is_refused():
    # Mesa's llvmpipe through EGL: what a Debian box without mesa-vulkan-drivers offers
    assert pick_adapter([_info("llvmpipe", "OpenGL", "CPU")]) == -1
    assert pick_adapter([]) == -1


def test_vulkan_beats_opengl_and_a_gpu_beats_a_cpu_driver():
    infos = [
        _info("llvmpipe", "OpenGL", "CPU"),
        _info("llvmpipe", "Vulkan", "CPU"),
        _info("NVIDIA H100", "Vulkan", "DiscreteGPU"),
        _info("NVIDIA H100", "OpenGL", "DiscreteGPU"),
    ]
    assert pick_adapter(infos) == 2
    assert pick_adapter(infos[:2]) == 1


def test_within_a_kind_enumeration_order_wins():
    infos = [_info("gpu0", "Vulkan", "DiscreteGPU"), _info("gpu1", "Vulkan", "DiscreteGPU")]
    assert pick_adapter(infos) == 0
    assert pick_adapter([_info("x", "Vulkan", "Unknown")]) == 0


def test_the_kind_of_device_matters_more_than_the_backend():
    infos = [_info("llvmpipe", "Vulkan", "CPU"), _info("dgpu", "D3D12", "DiscreteGPU")]
    assert pick_adapter(infos) == 1
