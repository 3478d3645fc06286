% Runs the ADD v4.2 reference implementation's ARAIM epoch
% (4datascience/ARAIM-Fault-Detection, araim_matlab/lib/araim_baseline_v4_2.m)
% on every user-epoch of the MAAST world grid, as our engine formed them
% (examples/dump_sky.rs --by-latitude: WORK/sky_lat<LAT>.csv), one
% latitude band at a time, writing WORK/ref_<VARIANT>_lat<LAT>.csv
% (case,modes,vpl_m,hpl_m); a band whose output exists is skipped, so a
% stopped run resumes. VARIANT:
%   published  the reference as published, with our C_int and C_acc;
%   all        as published, with every single-event mode monitored
%              (global PHMI 5e-9, below every prior: the reference's
%              fault-mode rule then stops at none of them; ADD v3.0's
%              rule), the bisection to its 0.05 m tolerance;
%   v3         the reference's functions composed per ADD v3.0
%              (v3_composed.m: every single event, ADD v3.0's P_unmon,
%              PL roots to 1e-6 m); run with SHADOW (modnormcdf = the
%              normal cdf) to remove the last known difference;
%   refmodel   as published, with the reference's own error model (its
%              trop_mops, its GPS af_cnmp_mops times the L1/L5 factor,
%              its Galileo E1/E5a table iono_gal) in place of ours.
% The parameters are availability_maast_compare.m's (ADD v3.0's LPV-200
% values; that file's header says which global is which).
% Usage (scripts/availability_maast_world.sh):
%   octave-cli --eval "availability_maast_world('REF/araim_matlab/lib', 'WORK', 'VARIANT', SHADOW, LATS)"
function availability_maast_world(ref_lib, work, variant, shadow, lats)
addpath(genpath(ref_lib));
if !isempty(shadow)
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
if strcmp(variant, 'all')
  PHMI = 5e-9;
end
for lat = lats
  name = fullfile(work, sprintf('ref_%s_lat%d.csv', variant, lat));
  if exist(name, 'file')
    continue;
  end
  sky = dlmread(fullfile(work, sprintf('sky_lat%d.csv', lat)), ',', 1, 0);
  last = [find(diff(sky(:, 1))); size(sky, 1)];
  first = [1; last(1:end - 1) + 1];
  res = zeros(numel(last), 4);
  t0 = tic;
  for k = 1:numel(last)
    r = sky(first(k):last(k), :);
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
    modes = NaN;
    switch variant
      case {'published', 'all'}
        subsets = determine_subsets_v4_2(G, psat, pconst, gi, ei, PTHRES, FC);
        modes = size(subsets, 1) - 1;
        [vpl, hpl] = araim_baseline_v4_2(G, cint, cacc, bnom, zeros(size(bnom)), psat, pconst, gi, ei);
      case 'v3'
        try
          [vpl, hpl] = v3_composed(G, cint, cacc, bnom, psat, pconst, gi, ei);
          modes = numel(psat) + numel(pconst);
        catch
          vpl = NaN; hpl = NaN;
        end
      case 'refmodel'
        v_ours = cacc - (2/3)^2;
        ura2 = cint - v_ours;
        v_ref = trop_mops(el);
        v_ref(1:ngps) = v_ref(1:ngps) + GAMMA_L1_L5 * iono_mops(NaN, el(1:ngps));
        v_ref(ei) = v_ref(ei) + iono_gal(el(ei));
        [vpl, hpl] = araim_baseline_v4_2(G, ura2 + v_ref, (2/3)^2 + v_ref, bnom, zeros(size(bnom)), psat, pconst, gi, ei);
      otherwise
        error('unknown variant %s', variant);
    end
    res(k, :) = [r(1, 1), modes, vpl, hpl];
  end
  t = toc(t0);
  out = fopen([name '.part'], 'w');
  fprintf(out, 'case,modes,vpl_m,hpl_m\n');
  fprintf(out, '%d,%d,%.17g,%.17g\n', res');
  fclose(out);
  rename([name '.part'], name);
  printf('%s lat %d: %d user-epochs in %.1f s: %.1f user-epochs/s\n', variant, lat, numel(last), t, numel(last) / t);
  fflush(stdout);
end
end
