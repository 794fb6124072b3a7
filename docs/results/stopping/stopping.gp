# Written by hbirl; run `gnuplot /tmp/re/stopping.gp` to redraw.
$curve << EOD
1 0.366667 0.385397
2 0.4 0.430106
3 0.366667 0.416381
4 0.433333 0.439298
5 0.45 0.488902
6 0.517241 0.517485
7 0.555556 0.570597
8 0.58 0.575502
9 0.545455 0.58183
10 0.511628 0.579158
11 0.534884 0.574933
12 0.512195 0.538925
13 0.583333 0.588004
14 0.571429 0.574978
15 0.545455 0.538101
16 0.53125 0.571546
17 0.612903 0.570955
18 0.533333 0.578301
19 0.482759 0.617992
20 0.517241 0.603574
21 0.571429 0.606705
22 0.555556 0.617563
23 0.6 0.579134
24 0.625 0.588862
25 0.681818 0.605651
26 0.65 0.617716
27 0.647059 0.655162
28 0.647059 0.654336
29 0.666667 0.622897
30 0.666667 0.647891
31 0.666667 0.621932
32 0.7 0.611974
33 0.875 0.727695
34 0.75 0.688846
35 0.833333 0.751583
36 0.8 0.721047
37 0.8 0.710187
EOD
$stop0 << EOD
12 1
3 1
11 1
5 1
27 0
5 1
4 1
3 1
38 1
3 1
3 1
9 1
23 1
13 1
31 1
8 1
23 1
7 1
5 0
EOD
$stop1 << EOD
12 1
3 1
11 1
6 1
27 0
5 1
5 1
3 1
3 1
3 1
18 1
24 1
8 1
28 1
8 1
EOD
set terminal pngcairo size 1000,900 noenhanced font 'sans,11'
set output '/tmp/re/stopping.png'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'Random tasks while watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
set key top right
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
set terminal svg size 1000,900 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/re/stopping.svg'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'Random tasks while watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
set key top right
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
unset output
