% Runs the ADD v4.2 reference implementation's ARAIM epoch
% (4datascience/ARAIM-Fault-Detection, araim_matlab/lib/araim_baseline_v4_2.m)
% on the user-epochs our engine dumped (examples/dump_sky.rs), three times:
%   1. with our C_int and C_acc (the same inputs: engine against engine);
%   2. as 1, with every single-event mode monitored, as ADD v3.0 does:
%      the reference monitors the single events in decreasing prior
%      only until the unmonitored probability is below P_THRES, or while
%      a prior exceeds PHMI; its global PHMI is used for nothing else, so
%      PHMI 5e-9 (below every prior here) makes it monitor them all;
%   3. as 2, with the PL bisection run to 1e-6 m (the roots);
%   4. the reference's own functions composed as ADD v3.0 does, with
%      every single event monitored and P_unmon = P(two or more events)
%      = 1 - prod(1 - p) - sum_i p_i prod_{j != i} (1 - p_j) (the
%      reference's determine_subsets_v4_2 counts each constellation mode
%      at P_const instead of P_const prod(1 - p_j) when it subtracts the
%      modes from P_unmon, which drives P_unmon to about zero or below:
%      -5.5e-9 on App. D instead of 3.45e-8), roots to 1e-6 m;
%   5. with the reference's own error model (its trop_mops, its GPS
%      af_cnmp_mops times the L1/L5 factor, its Galileo E1/E5a table).
% Its parameters are set to ADD v3.0's LPV-200 values so that the two
% algorithms, not their settings, are compared: no exposure-time
% multipliers (mean fault durations infinite), one effective sample
% (NES 1), no fault consolidation (FC 0), PHMI_V 9.8e-8, PHMI_H 2e-9,
% P_FA,V 3.9e-6, P_FA,H 9e-8, P_THRES 8e-8, TOL_PL 0.05 m, and the
% bisection run to its tolerance (NITER 200).
% Usage (scripts/availability_maast_compare.sh):
%   octave-cli --eval "availability_maast_compare('REF/araim_matlab/lib', 'WORK', SHADOW)"
% SHADOW, when not empty, is a directory put ahead of the reference's
% functions (the script's diagnostic: its own modnormcdf).
function availability_maast_compare(ref_lib, work, shadow)
addpath(genpath(ref_lib));
if nargin > 2 && !isempty(shadow)
  addpath(shadow);
end
warning('off', 'all');
global PTHRES FC PFA_V PFA_H TOL_PL PHMI_V PHMI_H PHMI NES_INT NES_CONT NITER TEXP_INT
global ARAIM_MFD_SAT_GPS ARAIM_MFD_SAT_GAL ARAIM_MFD_CONST_GPS ARAIM_MFD_CONST_GAL
global GAMMA_L1_L5
PHMI_V = 9.8e-8; PHMI_H = 2e-9; PHMI = PHMI_V + PHMI_H;
PFA_V = 3.9e-6; PFA_H = 9e-8; PTHRES = 8e-8; FC = 0; TOL_PL = 5e-2; NITER = 200;
NES_INT = 1; NES_CONT = 1; TEXP_INT = 0;
ARAIM_MFD_SAT_GPS = Inf; ARAIM_MFD_SAT_GAL = Inf;
ARAIM_MFD_CONST_GPS = Inf; ARAIM_MFD_CONST_GAL = Inf;
f1 = 1575.42e6; f5 = 1176.45e6;
GAMMA_L1_L5 = (f1^4 + f5^4) / (f1^2 - f5^2)^2;
init_cnmp_mops;
% ADD v3.0 Appendix D (SPEC 9.1; published: VPL 19.2 m, HPL 14.5 m, roots
% 19.217 m and 14.416 m), every single event monitored, to 1e-6 m.
D = [0.0225 0.9951 -0.0966 3.8865 3.5740; 0.6750 -0.6900 -0.2612 1.4377 1.1252;
     0.0723 -0.6601 -0.7477 0.8604 0.5479; -0.9398 0.2553 -0.2269 1.6383 1.3258;
     -0.5907 -0.7539 -0.2877 1.3229 1.0104; -0.3236 -0.0354 -0.9455 0.8434 0.5309;
     -0.6748 0.4356 -0.5957 0.8963 0.5838; 0.0938 -0.7004 -0.7075 0.8669 0.5544;
     0.5571 0.3088 -0.7709 0.8573 0.5448; 0.6622 0.6958 -0.2780 1.3616 1.0491];
GD = [D(:, 1:3), [ones(5, 1); zeros(5, 1)], [zeros(5, 1); ones(5, 1)]];
PHMI = 5e-9; TOL_PL = 1e-6;
[vd, hd] = araim_baseline_v4_2(GD, D(:, 4), D(:, 5), 0.5 * ones(10, 1), zeros(10, 1), ...
                               1e-5 * ones(10, 1), [1e-4; 1e-4], 1:5, 6:10);
printf('ADD v3.0 App. D through the reference: VPL %.4f m, HPL %.4f m (roots)\n', vd, hd);
[vd, hd, pr, p3] = v3_composed(GD, D(:, 4), D(:, 5), 0.5 * ones(10, 1), 1e-5 * ones(10, 1), [1e-4; 1e-4], 1:5, 6:10);
printf('App. D, the reference''s functions with P_unmon %.4g (theirs %.4g): VPL %.4f m, HPL %.4f m\n', p3, pr, vd, hd);
PHMI = PHMI_V + PHMI_H; TOL_PL = 5e-2;
sky = dlmread(fullfile(work, 'sky.csv'), ',', 1, 0);
cases = unique(sky(:, 1));
out = fopen(fullfile(work, 'ref.csv'), 'w');
fprintf(out, 'case,modes,vpl_m,hpl_m,modes_all,vpl_all_m,hpl_all_m,vpl_root_m,hpl_root_m,vpl_v3_m,hpl_v3_m,p_unmon_ref,p_unmon_v3,vpl_refmodel_m,hpl_refmodel_m,max_dcint_gps_m2\n');
t0 = tic;
for c = cases'
  r = sky(sky(:, 1) == c, :);
  sys = r(:, 2);
  gps = find(sys == 1); gal = find(sys == 2);
  r = r([gps; gal], :);
  ngps = numel(gps); ngal = numel(gal);
  G = [r(:, 4:6), [ones(ngps, ngps > 0); zeros(ngal, ngps > 0)], ...
       [zeros(ngps, ngal > 0); ones(ngal, ngal > 0)]];
  el = r(:, 7); cint = r(:, 8); cacc = r(:, 9); bnom = r(:, 10); psat = r(:, 11);
  pconst = [];
  if ngps > 0, pconst = [pconst; r(1, 12)]; end
  if ngal > 0, pconst = [pconst; r(end, 12)]; end
  gi = 1:ngps; ei = ngps + 1:ngps + ngal;
  subsets = determine_subsets_v4_2(G, psat, pconst, gi, ei, PTHRES, FC);
  [vpl, hpl] = araim_baseline_v4_2(G, cint, cacc, bnom, zeros(size(bnom)), psat, pconst, gi, ei);
  PHMI = 5e-9;
  subsets_all = determine_subsets_v4_2(G, psat, pconst, gi, ei, PTHRES, FC);
  [vpl_all, hpl_all] = araim_baseline_v4_2(G, cint, cacc, bnom, zeros(size(bnom)), psat, pconst, gi, ei);
  TOL_PL = 1e-6;
  [vpl_root, hpl_root] = araim_baseline_v4_2(G, cint, cacc, bnom, zeros(size(bnom)), psat, pconst, gi, ei);
  [vpl_v3, hpl_v3, pn_ref, pn_v3] = v3_composed(G, cint, cacc, bnom, psat, pconst, gi, ei);
  TOL_PL = 5e-2;
  PHMI = PHMI_V + PHMI_H;
  % The reference's own error model: URA^2 as we used it, plus its
  % troposphere and its airborne curve (sigma_URE 2/3 m, the comparison
  % run's, in C_acc).
  v_ours = cacc - (2/3)^2;          % our tropo + airborne variance
  ura2 = cint - v_ours;             % URA^2 as we used it
  v_ref = trop_mops(el);
  v_ref(1:ngps) = v_ref(1:ngps) + GAMMA_L1_L5 * iono_mops(NaN, el(1:ngps));
  v_ref(ei) = v_ref(ei) + iono_gal(el(ei));
  [vpl2, hpl2] = araim_baseline_v4_2(G, ura2 + v_ref, (2/3)^2 + v_ref, bnom, zeros(size(bnom)), psat, pconst, gi, ei);
  dgps = 0;
  if ngps > 0, dgps = max(abs(v_ref(1:ngps) - v_ours(1:ngps))); end
  fprintf(out, '%d,%d,%.17g,%.17g,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.6g,%.6g,%.17g,%.17g,%.3g\n', ...
          c, size(subsets, 1) - 1, vpl, hpl, size(subsets_all, 1) - 1, vpl_all, hpl_all, ...
          vpl_root, hpl_root, vpl_v3, hpl_v3, pn_ref, pn_v3, vpl2, hpl2, dgps);
end
t = toc(t0);
fclose(out);
printf('%d user-epochs, each run five times, in %.1f s: %.1f user-epochs/s per run\n', numel(cases), t, 5 * numel(cases) / t);
end
