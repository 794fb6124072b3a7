# Written by hbirl; run `gnuplot docs/results/onion/onion.gp` to redraw.
$m0 << EOD
1 5.38966 0.685941
2 2.15369 0.607488
3 1.89207 0.680671
4 0.51838 0.319343
5 0.146793 0.186232
6 0.127293 0.182709
7 0.176586 0.246506
8 0.0195 0.0386922
9 0.0195 0.0386922
10 0 0
EOD
$m1 << EOD
1 6.87926 0.830897
2 3.204 0.797862
3 1.76369 0.674042
4 0.754552 0.467606
5 0.196086 0.248974
6 0.0882932 0.175193
7 0.0195 0.0386922
8 0 0
9 0 0
10 0 0
EOD
$m2 << EOD
1 4.83931 0.677104
2 2.42886 0.66095
3 1.68569 0.635772
4 0.51838 0.319343
5 0.215586 0.251359
6 0.0585 0.0663365
7 0.107793 0.179033
8 0.0195 0.0386922
9 0.0195 0.0386922
10 0 0
EOD
$m3 << EOD
1 5.25207 0.685392
2 2.29128 0.635375
3 1.41052 0.565798
4 0.587173 0.358393
5 0.20069 0.213283
6 0.0585 0.0663365
7 0.107793 0.179033
8 0.0195 0.0386922
9 0.0882932 0.175193
10 0 0
EOD
$m4 << EOD
1 3.009 0.757485
2 1.75448 0.672066
3 1.26481 0.624154
4 0.224793 0.230809
5 0.0882932 0.175193
6 0.0195 0.0386922
7 0.107793 0.213885
8 0 0
9 0 0
10 0 0
EOD
set title 'Onion sorting: ILE vs trajectories (100 runs per point, 95% CI)'
set xlabel 'Number of trajectories'
set ylabel 'ILE'
set key right center box opaque
set grid
set yrange [0:*]
set xrange [0.5:10.5]
set style line 1 lc rgb '#1b9e77' lw 2 pt 7 ps 1.0
set style line 2 lc rgb '#d95f02' lw 2 pt 5 ps 1.0
set style line 3 lc rgb '#7570b3' lw 2 pt 9 ps 1.1
set style line 4 lc rgb '#e7298a' lw 2 pt 11 ps 1.1
set style line 5 lc rgb '#66a61e' lw 2 pt 13 ps 1.1
set style line 6 lc rgb '#e6ab02' lw 2 pt 3 ps 1.0
set terminal pngcairo size 900,600 font 'sans,11'
set output 'docs/results/onion/onion.png'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'ML Trajectories', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'ML Observations', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Uniform eta'
set terminal svg size 900,600 font 'sans,11' background rgb 'white'
set output 'docs/results/onion/onion.svg'
replot
unset output
