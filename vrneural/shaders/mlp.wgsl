// Unrolled MLP macros. Included by kernels that evaluate a network with constant weights.
// mlp_body(prefix, inputs, layers, T) defines `let {prefix}{layer}_{unit}` values; the outputs
// of the last layer are `{prefix}{n_layers}_{k}`. Zero weights are skipped (cost follows the net).
//
// Hoisting (first_base, first_cols): a first layer W [a | b] x + c whose inputs split into a part
// that changes in a loop (a: directions, per light) and a part that does not (b: neural-texture
// features) is evaluated as  W_a a + (c + W_b b),  where the bracket is computed once outside
// the loop by affine(). mlp_body then gets the bracket's names as first_base (one expression per
// first-layer unit) and only the loop-varying input columns as first_cols. Same function, fewer
// multiply-adds per light.
{% macro mlp_body(prefix, inputs, layers, T, first_base=none, first_cols=none) %}
{% for layer in layers %}
{% set li = loop.index %}
{% for o in range(layer.n_out) %}
{% set terms = [] %}
{% set cols = first_cols if (li == 1 and first_cols is not none) else range(layer.n_in) %}
{% for i in cols %}
{% if layer.weight[o][i] != 0.0 %}
{% set src = inputs[i] if li == 1 else prefix ~ (li - 1) ~ '_' ~ i %}
{% set _ = terms.append((layer.weight[o][i] | wgsl(T)) ~ ' * ' ~ src) %}
{% endif %}
{% endfor %}
{% set base = first_base[o] if (li == 1 and first_base is not none) else (layer.bias[o] | wgsl(T)) %}
{% set pre = ([base] + terms) | join(' + ') %}
{% if layer.act == 'relu' %}
    let {{ prefix }}{{ li }}_{{ o }} = max({{ pre }}, {{ T }}(0));
{% elif layer.act == 'leaky_relu' %}
    let {{ prefix }}{{ li }}_{{ o }}_p = {{ pre }};
    let {{ prefix }}{{ li }}_{{ o }} = max({{ prefix }}{{ li }}_{{ o }}_p, {{ T }}(0.01) * {{ prefix }}{{ li }}_{{ o }}_p);
{% else %}
    let {{ prefix }}{{ li }}_{{ o }} = {{ pre }};
{% endif %}
{% endfor %}
{% endfor %}
{% endmacro %}

{# The pre-activation part of one layer over input columns `cols` (inputs[i] for i in cols),
   with or without the bias, as `let {prefix}_{unit}`; no activation. #}
{% macro affine(prefix, inputs, layer, cols, T, with_bias) %}
{% for o in range(layer.n_out) %}
{% set terms = [] %}
{% for i in cols %}
{% if layer.weight[o][i] != 0.0 %}
{% set _ = terms.append((layer.weight[o][i] | wgsl(T)) ~ ' * ' ~ inputs[i]) %}
{% endif %}
{% endfor %}
{% set base = [layer.bias[o] | wgsl(T)] if with_bias else [] %}
{% set parts = base + terms %}
    let {{ prefix }}_{{ o }} = {{ (parts | join(' + ')) if parts else (T ~ '(0)') }};
{% endfor %}
{% endmacro %}
