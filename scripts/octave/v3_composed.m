% The ADD v4.2 reference implementation's functions composed per ADD
% v3.0 (availability_maast_compare.m run 4, availability_maast_world.m
% variant v3): its
% subsets with every single event (global PHMI below every prior), its
% subset solutions and thresholds, its PL bisection to 1e-6 m, with
% P_unmon the exact probability of two or more events (N_fault,max = 1
% here: checked, every mode is a single event).
function [vpl, hpl, pn_ref, pn] = v3_composed(G, cint, cacc, bnom, psat, pconst, gi, ei)
global PTHRES FC PFA_V PFA_H PHMI_V PHMI_H PHMI
PHMI = 5e-9;
[subsets, pap, ~, pn_ref] = determine_subsets_v4_2(G, psat, pconst, gi, ei, PTHRES, FC);
p = [psat; pconst];
if size(subsets, 1) - 1 != numel(p)
  error('v3_composed: %d modes for %d events (N_fault,max > 1)', size(subsets, 1) - 1, numel(p));
end
pn = 1 - prod(1 - p) - sum(p .* prod(1 - p) ./ (1 - p));
[sigma, sigma_ss, bias, bias_ss] = compute_subset_solutions(G, cint, cacc, bnom, zeros(size(bnom)), subsets);
[T1, T2, T3] = compute_test_thresholds(sigma_ss, bias_ss, PFA_V, PFA_H);
pf = pap; pf(1) = 2;
k = 1 - pn / (PHMI_V + PHMI_H);
vpl = compute_protection_level_v4_2(sigma(:, 3), bias(:, 3) + T3, pf, PHMI_V * k, 1e-6);
h1 = compute_protection_level_v4_2(sigma(:, 1), bias(:, 1) + T1, pf, PHMI_H / 2 * k, 1e-6);
h2 = compute_protection_level_v4_2(sigma(:, 2), bias(:, 2) + T2, pf, PHMI_H / 2 * k, 1e-6);
hpl = sqrt(h1^2 + h2^2);
end
