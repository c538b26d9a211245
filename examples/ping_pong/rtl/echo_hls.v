// An echo in the shape Vitis HLS gives: upper-case stream names, ap_clk, active-low ap_rst_n,
// one register stage (a full skid buffer) between the input and the output.
module echo_hls #(parameter STAGES = 1) (
    input  wire        ap_clk,
    input  wire        ap_rst_n,
    input  wire [63:0] send_TDATA,
    input  wire [7:0]  send_TKEEP,
    input  wire        send_TLAST,
    input  wire        send_TVALID,
    output wire        send_TREADY,
    output reg  [63:0] recv_TDATA,
    output reg  [7:0]  recv_TKEEP,
    output reg         recv_TLAST,
    output reg         recv_TVALID,
    input  wire        recv_TREADY
);
    assign send_TREADY = !recv_TVALID || recv_TREADY;
    always @(posedge ap_clk) begin
        if (!ap_rst_n) begin
            recv_TVALID <= 1'b0;
        end else if (send_TREADY) begin
            recv_TVALID <= send_TVALID;
            recv_TDATA <= send_TDATA;
            recv_TKEEP <= send_TKEEP;
            recv_TLAST <= send_TLAST;
        end
    end
endmodule
