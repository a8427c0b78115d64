// Unrolled MLP macro. Included by kernels that evaluate a network with constant weights.
// mlp_body(prefix, inputs, layers, T) defines `let {prefix}{layer}_{unit}` values; the outputs
// of the last layer are `{prefix}{n_layers}_{k}`. Zero weights are skipped (cost follows the net).
{% macro mlp_body(prefix, inputs, layers, T) %}
{% for layer in layers %}
{% set li = loop.index %}
{% for o in range(layer.n_out) %}
{% set terms = [] %}
{% for i in range(layer.n_in) %}
{% if layer.weight[o][i] != 0.0 %}
{% set src = inputs[i] if li == 1 else prefix ~ (li - 1) ~ '_' ~ i %}
{% set _ = terms.append((layer.weight[o][i] | wgsl(T)) ~ ' * ' ~ src) %}
{% endif %}
{% endfor %}
{% set pre = ([layer.bias[o] | wgsl(T)] + terms) | join(' + ') %}
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
